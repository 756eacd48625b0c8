#pragma once
// libtorch runtime setup. The Debian libtorch starts with a single intra-op thread on this kind of
// machine, and picks its AVX2 kernels even on AVX-512 CPUs; both make the networks slower than they
// need to be.
namespace u3d::nn {

// Applies `threads` (<= 0: u3d::default_thread_count()) to libtorch's intra-op pool, and to the
// inter-op pool the first time it is called (libtorch refuses to resize that pool once it is used).
// It also asks libtorch for its AVX-512 kernels (ATEN_CPU_CAPABILITY=avx512) when the CPU has them
// and the user did not set that variable; libtorch 1.13 would not check the CPU itself. libtorch fixes
// its kernel choice at its first operation, so call this before running any network.
// It also calls u3d::keep_freed_memory_for_reuse() (core/memory.h) and, except in AddressSanitizer
// builds, install_tensor_allocator() (nn/tensor_allocator.h).
// Returns the intra-op thread count now in effect.
int configure_torch_threads(int threads = 0);

// Whether this CPU has the instruction sets ATen's AVX-512 kernels use.
bool cpu_runs_avx512_kernels();

}  // namespace u3d::nn
