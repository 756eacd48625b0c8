#pragma once
// Thread setup shared by every entry point: OpenMP (our loops) and libtorch (the networks) each get
// the machine's cores, and nested parallel regions are off so the two never oversubscribe.
namespace u3d {

// Number of worker threads to use: UNIQUE3D_THREADS if set, else the hardware core count.
int default_thread_count();

// Applies `threads` (<= 0: default_thread_count()) to OpenMP. The nn module applies it to libtorch.
void configure_threads(int threads = 0);

}  // namespace u3d
