#pragma once
// What the layers that call oneDNN directly share (nn/layers/onednn_conv.h, nn/models/rrdbnet_cpu.h):
// the CPU engine, and the key that tells whether a weight tensor's contents changed since its packed
// copy was made. Included by their .cpp files only.
#include <torch/torch.h>
#include <dnnl.hpp>

namespace u3d::nn {

// The one CPU engine of the process.
dnnl::engine& onednn_cpu_engine();

// What identifies a weight tensor's contents: replacing the tensor (set_data, a new load) changes the
// storage, an in-place copy changes the version. Inference tensors (made under InferenceMode, e.g. a
// model converted there) have no version counter; they cannot be modified outside InferenceMode.
struct WeightKey {
  const void* data = nullptr;
  int64_t version = -1;
  bool operator==(const WeightKey&) const = default;
};
WeightKey weight_key(const torch::Tensor& weight);

}  // namespace u3d::nn
