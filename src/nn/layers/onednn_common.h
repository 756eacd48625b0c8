#pragma once
// What the layers that call oneDNN directly share (nn/layers/onednn_conv.h, nn/models/rrdbnet_cpu.h):
// the CPU engine, reorders and primitive calls that finish before they return, and the key that tells
// whether a weight tensor's contents changed since its packed copy was made. Included by their .cpp
// files only.
#include <torch/torch.h>
#include <dnnl.hpp>

#include <unordered_map>

namespace u3d::nn {

// The one CPU engine of the process.
dnnl::engine& onednn_cpu_engine();

// `source` reordered into `target`'s layout (handles: the memory itself is shared); done when it returns.
void onednn_reorder(dnnl::memory source, dnnl::memory target);

// Runs `primitive` on `args`, done when it returns. The work space `scratchpad` describes (primitives
// made with scratchpad_mode::user) comes from libtorch's allocator, which keeps freed blocks for reuse
// (nn/tensor_allocator.h); oneDNN's own would stay allocated with every plan.
void onednn_execute(const dnnl::primitive& primitive, const dnnl::memory::desc& scratchpad,
                    std::unordered_map<int, dnnl::memory> args);

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
