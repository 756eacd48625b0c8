#pragma once
// The CPU allocator libtorch's tensors come from once install_tensor_allocator() has run. Blocks of
// kLargeBlockBytes and more (the networks' activations and most weights) get their own mappings; a
// freed one waits in a bounded cache and is unmapped when the cache would exceed its bound, so the
// memory the process holds beyond its live tensors stays within that bound. Smaller blocks go to
// libtorch's own allocator (glibc's heap).
//
// A request takes cached pages of any size: the smallest cached block that holds it, split, with the
// rest staying cached, or else the largest cached block grown to the size wanted (mremap moves its pages
// without touching them). Only pages beyond the cache's are new, and only new pages are faulted in on
// first write. With cached blocks served only to requests of their own size (within an eighth), a fp32
// UNet forward (bench_unet, batch 8 at 32x32) mapped a hundred blocks anew and took about 630k minor
// page faults: each fp32 convolution through ATen reorders its weights into a new buffer of 14-112 MiB,
// and a 112 MiB buffer flushed the rest of the cache (docs/networks.md, "Memory").
//
// New large blocks ask for transparent huge pages (madvise; where the system's THP setting is "madvise"
// or "always"): their first writes then fault 2 MiB at a time instead of 4 KiB. On the 2-core VMs here a
// first write to fresh memory costs ~4 s/GiB in 4 KiB pages and ~1.7 s/GiB in huge ones; the fp32 UNet
// forward (bench_unet) went from ~153k to ~11k minor faults.
//
// In glibc's heap the large blocks left holes that later blocks of other sizes could not use: a fp32
// refinement step at 1024 px held about 1 GiB more than its live tensors that way (docs/networks.md,
// "Memory"). Mapping each of them anew instead (a lower M_MMAP_THRESHOLD) faults their pages in again
// every time: the same step took 180 s against 149 s in one run each. Until 2026-12-07 the bound was
// 8 MiB, and the blocks of 1-8 MiB (a bf16 normal step's 32x32 and 16x16 activations, 2.6-5.2 MiB) came
// from the heap, where they left holes of the same kind: with 1 MiB that step's peak RSS went from 4.03
// to 3.80 GB (docs/networks.md, "Memory").
#include <cstddef>

namespace u3d::nn {

constexpr size_t kLargeBlockBytes = size_t{1} << 20;
constexpr size_t kLargeBlockCacheBytes = size_t{128} << 20;

// Makes this allocator libtorch's CPU allocator. Idempotent; tensors allocated before keep their own
// deleters, so it may be called at any time. Called by configure_torch_threads (nn/runtime.h), except
// in AddressSanitizer builds.
void install_tensor_allocator();

struct TensorAllocatorStats {
  size_t mapped_bytes = 0;   // large blocks mapped now, in use or cached
  size_t cached_bytes = 0;   // of which freed and waiting in the cache
  size_t reused_blocks = 0;  // large requests served from the cache so far
  size_t mapped_blocks = 0;  // large requests that mapped a new block so far
  size_t new_bytes = 0;      // bytes of new pages mapped so far (new blocks, and growth beyond cached pages)
};
TensorAllocatorStats tensor_allocator_stats();

}  // namespace u3d::nn
