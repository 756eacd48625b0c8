#include "nn/runtime.h"

#include <ATen/Parallel.h>

#include <cstdlib>
#include <mutex>

#include "core/parallel.h"

namespace u3d::nn {

int configure_torch_threads(int threads) {
  // libtorch 1.13 uses AVX2 kernels unless told otherwise. With AVX-512 the full UNet took about 15%
  // less CPU time here (bench_unet); overwrite=0 keeps a user's own choice.
  setenv("ATEN_CPU_CAPABILITY", "avx512", 0);
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
