#include "nn/layers/layers.h"

#include "nn/layers/group_norm_kernel.h"
#include "nn/layers/layer_norm_kernel.h"

namespace u3d::nn {

LinearImpl::LinearImpl(int64_t in_features, int64_t out_features, bool has_bias, const torch::TensorOptions& options) {
  weight = register_parameter("weight", torch::empty({out_features, in_features}, options), false);
  if (has_bias) bias = register_parameter("bias", torch::empty({out_features}, options), false);
}

namespace {

// The first (0) or second (1) half of a weight's rows or of a bias; undefined stays undefined.
torch::Tensor half(const torch::Tensor& t, int64_t which) {
  if (!t.defined()) return t;
  const int64_t n = t.size(0) / 2;
  return t.narrow(0, which * n, n);
}

}  // namespace

torch::Tensor LinearImpl::forward(const torch::Tensor& x) {
  if (OnednnLinear::applies(x, weight)) {
    if (!gate_onednn_) return onednn_->forward(x, weight, bias);
    return torch::cat({onednn_->forward(x, half(weight, 0), half(bias, 0)),
                       gate_onednn_->forward(x, half(weight, 1), half(bias, 1))},
                      -1);
  }
  TORCH_CHECK(!holds_packed_weights(), "linear: the weights are packed for oneDNN, which cannot take a ",
              x.scalar_type(), " input on ", x.device());
  return torch::linear(x, weight, bias);
}

void LinearImpl::pack_weights_in_place() {
  if (!gate_onednn_) return onednn_->pack_in_place(weight);
  onednn_->pack_in_place(half(weight, 0));
  gate_onednn_->pack_in_place(half(weight, 1));
}

void LinearImpl::split_output_halves() {
  TORCH_CHECK(weight.size(0) % 2 == 0, "linear: ", weight.size(0), " outputs do not split in halves");
  TORCH_CHECK(!holds_packed_weights(), "linear: the outputs are split in halves before the weights are packed");
  if (!gate_onednn_) gate_onednn_ = std::make_shared<OnednnLinear>();
}

bool LinearImpl::gated_forward_applies(const torch::Tensor& x) const {
  return gate_onednn_ && OnednnLinear::applies(x, weight);
}

torch::Tensor LinearImpl::gated_forward(const torch::Tensor& x) {
  TORCH_CHECK(gated_forward_applies(x), "linear: the gated product takes split halves and oneDNN's path");
  const torch::Tensor gelu_of_gate =
      gate_onednn_->forward(x, half(weight, 1), half(bias, 1), OnednnLinear::Epilogue::gelu);
  return onednn_->forward(x, half(weight, 0), half(bias, 0), OnednnLinear::Epilogue::multiply, gelu_of_gate);
}

bool LinearImpl::holds_packed_weights() const {
  return onednn_->holds_packed_weights() || (gate_onednn_ && gate_onednn_->holds_packed_weights());
}

Conv2dImpl::Conv2dImpl(int64_t in_channels, int64_t out_channels, int64_t kernel, int64_t stride_, int64_t padding_,
                       bool has_bias, const torch::TensorOptions& options)
    : stride(stride_), padding(padding_) {
  weight = register_parameter("weight", torch::empty({out_channels, in_channels, kernel, kernel}, options), false);
  if (has_bias) bias = register_parameter("bias", torch::empty({out_channels}, options), false);
}

torch::Tensor Conv2dImpl::forward(const torch::Tensor& x) {
  if (OnednnConv2d::applies(x, weight)) return onednn_->forward(x, weight, bias, stride, padding);
  return torch::conv2d(x, weight, bias, {stride, stride}, {padding, padding});
}

void Conv2dImpl::pack_weights_in_place() { onednn_->pack_in_place(); }

void pack_weights_in_place(torch::nn::Module& model) {
  for (const auto& module : model.modules(/*include_self=*/true)) {
    if (auto* conv = dynamic_cast<Conv2dImpl*>(module.get())) conv->pack_weights_in_place();
    if (auto* linear = dynamic_cast<LinearImpl*>(module.get())) linear->pack_weights_in_place();
  }
}

GroupNormImpl::GroupNormImpl(int64_t groups_, int64_t channels, double eps_, const torch::TensorOptions& options)
    : groups(groups_), eps(eps_) {
  TORCH_CHECK(channels % groups == 0, "GroupNorm: ", channels, " channels are not divisible into ", groups, " groups");
  weight = register_parameter("weight", torch::empty({channels}, options), false);
  bias = register_parameter("bias", torch::empty({channels}, options), false);
}

torch::Tensor GroupNormImpl::forward(const torch::Tensor& x) {
  if (group_norm_channels_last_applies(x, weight)) return group_norm_channels_last(x, groups, weight, bias, eps, false);
  if (x.scalar_type() == weight.scalar_type()) return torch::group_norm(x, groups, weight, bias, eps);
  // Reduced-precision activations, fp32 weights (nn/precision.h): statistics and scaling in fp32. NCHW:
  // ATen 1.13's fp32 GroupNorm of channels-last input loses precision at large offsets (docs/networks.md).
  return torch::group_norm(x.to(weight.scalar_type()).contiguous(), groups, weight, bias, eps).to(x.scalar_type());
}

torch::Tensor GroupNormImpl::forward_silu(const torch::Tensor& x) {
  if (group_norm_channels_last_applies(x, weight)) return group_norm_channels_last(x, groups, weight, bias, eps, true);
  torch::Tensor y = forward(x);
  return torch::silu_(y);
}

LayerNormImpl::LayerNormImpl(int64_t dim, double eps_, const torch::TensorOptions& options) : eps(eps_) {
  weight = register_parameter("weight", torch::empty({dim}, options), false);
  bias = register_parameter("bias", torch::empty({dim}, options), false);
}

torch::Tensor LayerNormImpl::forward(const torch::Tensor& x) {
  if (layer_norm_bf16_applies(x, weight, bias)) return layer_norm_bf16(x, weight, bias, eps);
  if (x.scalar_type() == weight.scalar_type()) return torch::layer_norm(x, {weight.size(0)}, weight, bias, eps);
  return torch::layer_norm(x.to(weight.scalar_type()), {weight.size(0)}, weight, bias, eps).to(x.scalar_type());
}

EmbeddingImpl::EmbeddingImpl(int64_t count, int64_t dim, const torch::TensorOptions& options) {
  weight = register_parameter("weight", torch::empty({count, dim}, options), false);
}

torch::Tensor EmbeddingImpl::forward(const torch::Tensor& indices) { return torch::embedding(weight, indices); }

void randomize_parameters(torch::nn::Module& module, double std) {
  torch::NoGradGuard no_grad;
  for (auto& p : module.parameters()) p.normal_(0.0, std);
}

}  // namespace u3d::nn
