#pragma once
// diffusers AutoencoderKL (SD 1.x VAE: DownEncoderBlock2D / UpDecoderBlock2D, mid block with one
// single-head attention), built from its config.json with diffusers' parameter names.
#include <nlohmann/json.hpp>
#include <string>
#include <torch/torch.h>
#include <vector>

#include "nn/attention.h"
#include "nn/layers.h"
#include "nn/tensor_map.h"
#include "nn/unet_blocks.h"

namespace u3d::nn {

struct AutoencoderKLConfig {
  int64_t in_channels = 3;
  int64_t out_channels = 3;
  std::vector<int64_t> block_out_channels;
  int64_t layers_per_block = 1;
  int64_t latent_channels = 4;
  int64_t norm_num_groups = 32;
  double scaling_factor = 0.18215;

  static AutoencoderKLConfig from_json(const nlohmann::json& json, const std::string& source);
};

// Checkpoints written by diffusers < 0.14 (e.g. the original sd-image-variations VAE) name the mid-block
// attention query / key / value / proj_attn; renames them to to_q / to_k / to_v / to_out.0 in place.
void convert_legacy_vae_attention_keys(TensorMap& state_dict);

// UNetMidBlock2D as the VAE uses it: resnet, attention (GroupNorm + residual, one head), resnet.
class VaeMidBlockImpl : public torch::nn::Module {
 public:
  VaeMidBlockImpl(int64_t channels, int64_t groups, const torch::TensorOptions& options);
  torch::Tensor forward(torch::Tensor h);
  std::vector<ResnetBlock2D> resnets;
  Attention attention{nullptr};
};
TORCH_MODULE(VaeMidBlock);

// DownEncoderBlock2D (downsample: asymmetric pad + stride-2 conv) or UpDecoderBlock2D (nearest x2 + conv).
class VaeBlockImpl : public torch::nn::Module {
 public:
  enum class Kind { Down, Up };
  VaeBlockImpl(Kind kind, int64_t in_channels, int64_t out_channels, int64_t layers, bool resample, int64_t groups,
               const torch::TensorOptions& options);
  torch::Tensor forward(torch::Tensor h);
  std::vector<ResnetBlock2D> resnets;
  Downsample2D downsampler{nullptr};
  Upsample2D upsampler{nullptr};
};
TORCH_MODULE(VaeBlock);

class VaeEncoderImpl : public torch::nn::Module {
 public:
  VaeEncoderImpl(const AutoencoderKLConfig& config, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& image);  // [N, 3, H, W] -> [N, 2·latent, H/f, W/f]
  Conv2d conv_in{nullptr}, conv_out{nullptr};
  std::vector<VaeBlock> down_blocks;
  VaeMidBlock mid_block{nullptr};
  GroupNorm conv_norm_out{nullptr};
};
TORCH_MODULE(VaeEncoder);

class VaeDecoderImpl : public torch::nn::Module {
 public:
  VaeDecoderImpl(const AutoencoderKLConfig& config, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& latent);
  Conv2d conv_in{nullptr}, conv_out{nullptr};
  VaeMidBlock mid_block{nullptr};
  std::vector<VaeBlock> up_blocks;
  GroupNorm conv_norm_out{nullptr};
};
TORCH_MODULE(VaeDecoder);

// The diagonal Gaussian the encoder predicts.
struct LatentDistribution {
  torch::Tensor mean;
  torch::Tensor logvar;  // clamped to [-30, 20] as diffusers does
  torch::Tensor std() const { return torch::exp(0.5 * logvar); }
  const torch::Tensor& mode() const { return mean; }
};

class AutoencoderKLImpl : public torch::nn::Module {
 public:
  AutoencoderKLImpl(const AutoencoderKLConfig& config, const torch::TensorOptions& options);

  // image [N, in_channels, H, W] in [-1, 1]; H and W multiples of 2^(blocks-1).
  LatentDistribution encode(const torch::Tensor& image);
  // latent [N, latent_channels, h, w] (unscaled: divide by scaling_factor first) -> image, about [-1, 1].
  torch::Tensor decode(const torch::Tensor& latent);

  AutoencoderKLConfig config;
  VaeEncoder encoder{nullptr};
  VaeDecoder decoder{nullptr};
  Conv2d quant_conv{nullptr}, post_quant_conv{nullptr};
};
TORCH_MODULE(AutoencoderKL);

}  // namespace u3d::nn
