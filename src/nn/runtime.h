#pragma once
// libtorch thread setup. The Debian libtorch starts with a single intra-op thread on this kind of
// machine, which makes the networks several times slower than they need to be.
namespace u3d::nn {

// Applies `threads` (<= 0: u3d::default_thread_count()) to libtorch's intra-op pool, and to the
// inter-op pool the first time it is called (libtorch refuses to resize that pool once it is used).
// Returns the intra-op thread count now in effect.
int configure_torch_threads(int threads = 0);

}  // namespace u3d::nn
