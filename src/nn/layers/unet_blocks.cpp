#include "nn/layers/unet_blocks.h"

#include <cmath>

namespace u3d::nn {

ResnetBlock2DImpl::ResnetBlock2DImpl(int64_t in_channels, int64_t out_channels, int64_t temb_channels, int64_t groups,
                                     double eps, const torch::TensorOptions& t) {
  norm1 = register_module("norm1", GroupNorm(groups, in_channels, eps, t));
  conv1 = register_module("conv1", Conv2d(in_channels, out_channels, 3, 1, 1, true, t));
  if (temb_channels > 0) time_emb_proj = register_module("time_emb_proj", Linear(temb_channels, out_channels, true, t));
  norm2 = register_module("norm2", GroupNorm(groups, out_channels, eps, t));
  conv2 = register_module("conv2", Conv2d(out_channels, out_channels, 3, 1, 1, true, t));
  if (in_channels != out_channels)
    conv_shortcut = register_module("conv_shortcut", Conv2d(in_channels, out_channels, 1, 1, 0, true, t));
}

torch::Tensor ResnetBlock2DImpl::forward(const torch::Tensor& x, const torch::Tensor& temb) {
  // In place where the result is fresh, so that at most the input and two maps of the block's size
  // are alive at once (the VAE at 1024 px: 0.5-1 GB each in fp32).
  torch::Tensor h = conv1->forward(norm1->forward_silu(x));
  if (time_emb_proj && temb.defined()) h.add_(time_emb_proj->forward(torch::silu(temb)).unsqueeze(-1).unsqueeze(-1));
  h = conv2->forward(norm2->forward_silu(h));
  return h.add_(conv_shortcut ? conv_shortcut->forward(x) : x);
}

Downsample2DImpl::Downsample2DImpl(int64_t channels, int64_t padding_, const torch::TensorOptions& t)
    : padding(padding_) {
  conv = register_module("conv", Conv2d(channels, channels, 3, 2, padding, true, t));
}

torch::Tensor Downsample2DImpl::forward(const torch::Tensor& x) {
  if (padding == 0) return conv->forward(torch::constant_pad_nd(x, {0, 1, 0, 1}, 0));
  return conv->forward(x);
}

Upsample2DImpl::Upsample2DImpl(int64_t channels, const torch::TensorOptions& t) {
  conv = register_module("conv", Conv2d(channels, channels, 3, 1, 1, true, t));
}

torch::Tensor Upsample2DImpl::forward(const torch::Tensor& x, c10::IntArrayRef size) {
  std::vector<int64_t> out_size = size.empty() ? std::vector<int64_t>{2 * x.size(2), 2 * x.size(3)} : size.vec();
  return conv->forward(torch::upsample_nearest2d(x, out_size));
}

torch::Tensor timestep_projection(const torch::Tensor& timesteps, int64_t dim, bool flip_sin_to_cos,
                                  double freq_shift) {
  TORCH_CHECK(timesteps.dim() == 1, "timesteps must be 1-D, got ", timesteps.sizes());
  const int64_t half = dim / 2;
  auto f32 = torch::TensorOptions().dtype(torch::kFloat).device(timesteps.device());
  // Same operation order as diffusers, in fp32, so the embedding is bit-identical.
  torch::Tensor exponent = torch::arange(0, half, f32) * static_cast<float>(-std::log(10000.0));
  exponent = exponent / static_cast<float>(half - freq_shift);
  torch::Tensor emb = timesteps.unsqueeze(1).to(torch::kFloat) * torch::exp(exponent).unsqueeze(0);
  emb = flip_sin_to_cos ? torch::cat({torch::cos(emb), torch::sin(emb)}, -1) : torch::cat({torch::sin(emb), torch::cos(emb)}, -1);
  if (dim % 2 == 1) emb = torch::constant_pad_nd(emb, {0, 1}, 0);
  return emb;
}

TimestepEmbeddingImpl::TimestepEmbeddingImpl(int64_t in_channels, int64_t dim, const torch::TensorOptions& t) {
  linear_1 = register_module("linear_1", Linear(in_channels, dim, true, t));
  linear_2 = register_module("linear_2", Linear(dim, dim, true, t));
}

torch::Tensor TimestepEmbeddingImpl::forward(const torch::Tensor& x) {
  return linear_2->forward(torch::silu(linear_1->forward(x)));
}

}  // namespace u3d::nn
