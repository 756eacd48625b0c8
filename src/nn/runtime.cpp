#include "nn/runtime.h"

#include <ATen/Parallel.h>

#include <mutex>

#include "core/parallel.h"

namespace u3d::nn {

int configure_torch_threads(int threads) {
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
