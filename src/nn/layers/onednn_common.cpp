#include "nn/layers/onednn_common.h"

namespace u3d::nn {

dnnl::engine& onednn_cpu_engine() {
  static dnnl::engine engine(dnnl::engine::kind::cpu, 0);
  return engine;
}

WeightKey weight_key(const torch::Tensor& weight) {
  return {weight.data_ptr(), weight.is_inference() ? -1 : static_cast<int64_t>(weight._version())};
}

}  // namespace u3d::nn
