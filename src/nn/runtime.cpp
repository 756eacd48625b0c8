#include "nn/runtime.h"

#include <ATen/Parallel.h>

#include <cstdlib>
#include <mutex>

#include "core/memory.h"
#include "core/parallel.h"
#include "core/sanitizer.h"
#include "nn/tensor_allocator.h"

namespace u3d::nn {

bool cpu_runs_avx512_kernels() {
  // What ATen's AVX-512 kernels are compiled for (its own detection in later versions checks these).
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("fma");
}

int configure_torch_threads(int threads) {
  u3d::keep_freed_memory_for_reuse();  // networks free and reallocate tens of MB every layer
  // ASan watches the bounds of malloc's blocks only, not of the tensor allocator's mappings.
  if (!kUnderAsan) install_tensor_allocator();
  // libtorch 1.13 uses AVX2 kernels unless told otherwise. With AVX-512 the full UNet took about 15%
  // less CPU time here (bench_unet); overwrite=0 keeps a user's own choice. ATen 1.13 takes the
  // variable on trust, so it is only set where the CPU has the instructions (else: SIGILL).
  if (cpu_runs_avx512_kernels()) setenv("ATEN_CPU_CAPABILITY", "avx512", 0);
  if (threads <= 0) threads = default_thread_count();
  at::set_num_threads(threads);
  // The inter-op pool can only be sized before its first use; later calls keep the first size.
  static std::once_flag interop_once;
  std::call_once(interop_once, [threads] {
    try {
      at::set_num_interop_threads(threads);
    } catch (const c10::Error&) {
      // Already started by an earlier parallel op: keep libtorch's own size.
    }
  });
  return at::get_num_threads();
}

}  // namespace u3d::nn
