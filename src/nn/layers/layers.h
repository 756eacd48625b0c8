#pragma once
// The basic parameterised layers, with the parameter names torch.nn uses (weight, bias).
// Unlike torch::nn's layers these allocate their parameters uninitialised (torch::empty) with the given
// options: every weight comes from a checkpoint anyway, a full UNet is not randomly initialised for
// nothing, and on the meta device nothing is allocated at all (used to check key names and shapes).
#include <torch/torch.h>

#include <memory>

#include "nn/layers/onednn_conv.h"
#include "nn/layers/onednn_linear.h"

namespace u3d::nn {

class LinearImpl : public torch::nn::Module {
 public:
  LinearImpl(int64_t in_features, int64_t out_features, bool bias, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  // bf16, or fp32 with AVX-512, on the CPU: pack the weights into their own storage
  // (OnednnLinear::pack_in_place).
  void pack_weights_in_place();
  torch::Tensor weight, bias;  // bias undefined when disabled

  // For GEGLU's projection (nn/layers/transformer_2d.h), whose outputs are [hidden | gate]: from now on
  // oneDNN computes the two halves as two products, each with its half of the weights (packed on its
  // own), so that gated_forward can apply the gating as the outputs are written. Before any packing.
  void split_output_halves();
  // Whether gated_forward takes `x`: the halves are split and oneDNN's path applies.
  bool gated_forward_applies(const torch::Tensor& x) const;
  // hidden * gelu(gate), [..., out/2], the exact GELU: the gate half's product goes through the GELU as
  // it is written, and the hidden half's is multiplied by that (in fp32, rounded once) as it is written,
  // so the [..., out] projection is never stored.
  torch::Tensor gated_forward(const torch::Tensor& x);

 private:
  bool holds_packed_weights() const;
  // bf16, or fp32 with AVX-512, on the CPU: oneDNN's matrix product directly (nn/layers/onednn_linear.h);
  // after split_output_halves, of the first half, and gate_onednn_ of the second.
  std::shared_ptr<OnednnLinear> onednn_ = std::make_shared<OnednnLinear>();
  std::shared_ptr<OnednnLinear> gate_onednn_;
};
TORCH_MODULE(Linear);

class Conv2dImpl : public torch::nn::Module {
 public:
  Conv2dImpl(int64_t in_channels, int64_t out_channels, int64_t kernel, int64_t stride, int64_t padding, bool bias,
             const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  // bf16 or fp32 on the CPU: pack the weights into their own storage (OnednnConv2d::pack_in_place).
  void pack_weights_in_place();
  torch::Tensor weight, bias;
  int64_t stride, padding;

 private:
  // bf16 or fp32 on the CPU: oneDNN directly, with the weights packed once (nn/layers/onednn_conv.h).
  std::shared_ptr<OnednnConv2d> onednn_ = std::make_shared<OnednnConv2d>();
};
TORCH_MODULE(Conv2d);

// pack_weights_in_place() on every Conv2d and Linear inside `model`: for a loaded network that only serves
// forward passes (OnednnConv2d::pack_in_place says what that gives up).
void pack_weights_in_place(torch::nn::Module& model);

// The norms compute in the dtype of their weights: fp32 weights normalise bf16/fp16 activations in
// fp32 and return the activations' dtype (nn/precision.h).
class GroupNormImpl : public torch::nn::Module {
 public:
  GroupNormImpl(int64_t groups, int64_t channels, double eps, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  // silu(forward(x)); one pass for channels-last bf16 activations (nn/layers/group_norm_kernel.h).
  torch::Tensor forward_silu(const torch::Tensor& x);
  torch::Tensor weight, bias;
  int64_t groups;
  double eps;
};
TORCH_MODULE(GroupNorm);

class LayerNormImpl : public torch::nn::Module {
 public:
  LayerNormImpl(int64_t dim, double eps, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  torch::Tensor weight, bias;
  double eps;
};
TORCH_MODULE(LayerNorm);

class EmbeddingImpl : public torch::nn::Module {
 public:
  EmbeddingImpl(int64_t count, int64_t dim, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& indices);
  torch::Tensor weight;
};
TORCH_MODULE(Embedding);

// Fills every parameter of `module` with N(0, std^2) (deterministic given torch::manual_seed);
// for benchmarks and tests that need a full-size network without a checkpoint.
void randomize_parameters(torch::nn::Module& module, double std);

}  // namespace u3d::nn
