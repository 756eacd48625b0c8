#pragma once
// Building blocks shared by the UNet and the VAE, named as in diffusers: ResnetBlock2D, Downsample2D,
// Upsample2D, the sinusoidal timestep projection and TimestepEmbedding.
#include <torch/torch.h>

#include "nn/layers/layers.h"

namespace u3d::nn {

// diffusers ResnetBlock2D ("default" time-scale-shift, SiLU, output scale 1):
// out = shortcut(x) + conv2(silu(norm2(conv1(silu(norm1(x))) + time_emb_proj(silu(temb))))).
class ResnetBlock2DImpl : public torch::nn::Module {
 public:
  // temb_channels 0: no time embedding input (VAE).
  ResnetBlock2DImpl(int64_t in_channels, int64_t out_channels, int64_t temb_channels, int64_t groups, double eps,
                    const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& temb = {});

  GroupNorm norm1{nullptr}, norm2{nullptr};
  Conv2d conv1{nullptr}, conv2{nullptr}, conv_shortcut{nullptr};
  Linear time_emb_proj{nullptr};
};
TORCH_MODULE(ResnetBlock2D);

// 3x3 convolution with stride 2. padding 0 is the VAE encoder's variant: the input is first padded by
// one zero row/column at the bottom/right only (asymmetric), as diffusers does.
class Downsample2DImpl : public torch::nn::Module {
 public:
  Downsample2DImpl(int64_t channels, int64_t padding, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  Conv2d conv{nullptr};
  int64_t padding;
};
TORCH_MODULE(Downsample2D);

// Nearest-neighbour upsampling, then a 3x3 convolution.
class Upsample2DImpl : public torch::nn::Module {
 public:
  Upsample2DImpl(int64_t channels, const torch::TensorOptions& options);
  // size: the output height/width (the matching skip connection's); empty: exactly x2.
  torch::Tensor forward(const torch::Tensor& x, c10::IntArrayRef size = {});
  Conv2d conv{nullptr};
};
TORCH_MODULE(Upsample2D);

// Sinusoidal projection of timesteps [N] (float or integer) -> fp32 [N, dim] as diffusers `Timesteps`:
// frequencies exp(-ln(10000)·i/(dim/2 - freq_shift)), [sin, cos] halves, swapped to [cos, sin] when
// flip_sin_to_cos.
torch::Tensor timestep_projection(const torch::Tensor& timesteps, int64_t dim, bool flip_sin_to_cos,
                                  double freq_shift);

// diffusers TimestepEmbedding: linear_1 -> SiLU -> linear_2.
class TimestepEmbeddingImpl : public torch::nn::Module {
 public:
  TimestepEmbeddingImpl(int64_t in_channels, int64_t dim, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  Linear linear_1{nullptr}, linear_2{nullptr};
};
TORCH_MODULE(TimestepEmbedding);

}  // namespace u3d::nn
