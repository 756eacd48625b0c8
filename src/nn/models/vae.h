#pragma once
// diffusers AutoencoderKL (SD 1.x VAE: DownEncoderBlock2D / UpDecoderBlock2D, mid block with one
// single-head attention), built from its config.json with diffusers' parameter names.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <torch/torch.h>
#include <vector>

#include "nn/checkpoint/tensor_map.h"
#include "nn/layers/attention.h"
#include "nn/layers/layers.h"
#include "nn/layers/unet_blocks.h"

namespace u3d::nn {

struct AutoencoderKLConfig {
  int64_t in_channels = 3;
  int64_t out_channels = 3;
  std::vector<int64_t> block_out_channels;
  int64_t layers_per_block = 1;
  int64_t latent_channels = 4;
  int64_t norm_num_groups = 32;
  double scaling_factor = 0.18215;
  int64_t sample_size = 32;  // image side the VAE was trained at; sets diffusers' default decode tile

  // Factor between image and latent sides: 2^(blocks - 1) (8 for the SD VAE).
  int64_t scale_factor() const { return int64_t{1} << (block_out_channels.size() - 1); }

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

// Tiled decoding, as diffusers' AutoencoderKL.enable_tiling(): the latent is cut into square tiles with
// neighbours sharing `overlap` of a tile, each tile is decoded on its own, and each tile cross-fades
// linearly into its upper and left neighbours over the shared band before being cropped to its stride.
// Why: the decoder's activations grow with the pixel count. For the SD VAE at a 64x64 latent (512² image)
// the last up block works on 256- and 128-channel maps at 512², 128-256 MiB each in fp32 with several
// alive at once (about 1 GiB peak); a 2048² image needs 16 times that, and its mid-block attention runs
// over 16 times as many tokens. Decoding in tiles bounds the peak by one tile's decode plus the decoded
// (3-channel) tiles of two tile rows and the output, whatever the image size. The price: GroupNorm
// statistics and the mid-block attention see one tile instead of the whole image, so the result is
// close to, not equal to, the plain decode.
struct VaeTiling {
  int64_t tile_latent = 64;  // tile side in latent pixels (diffusers: sample_size / scale_factor)
  double overlap = 0.25;     // fraction of a tile shared with the next one (diffusers' tile_overlap_factor), <= 0.5
};

// Decodes `latent` [N, C, h, w] with `decode_tile` (a latent tile -> its image, `scale` times larger) in
// overlapping tiles; a latent that fits in one tile is decoded whole. Tiles start every
// floor(tile_latent·(1 - overlap)) latent pixels, and the blend band is the decoded overlap; for the
// diffusers defaults (tile 64, overlap 0.25) this is diffusers' tiled_decode. The result is [N, ·, h·scale, w·scale].
torch::Tensor decode_in_tiles(const torch::Tensor& latent, const VaeTiling& tiling, int64_t scale,
                              const std::function<torch::Tensor(const torch::Tensor&)>& decode_tile);

class AutoencoderKLImpl : public torch::nn::Module {
 public:
  AutoencoderKLImpl(const AutoencoderKLConfig& config, const torch::TensorOptions& options);

  // image [N, in_channels, H, W] in [-1, 1]; H and W multiples of 2^(blocks-1).
  LatentDistribution encode(const torch::Tensor& image);
  // latent [N, latent_channels, h, w] (unscaled: divide by scaling_factor first) -> image, about [-1, 1].
  torch::Tensor decode(const torch::Tensor& latent);
  // decode() in tiles (see VaeTiling); equal to decode() when the latent fits in one tile.
  torch::Tensor decode_tiled(const torch::Tensor& latent, const VaeTiling& tiling);
  // diffusers' tiling for this VAE: tiles of sample_size / scale_factor latent pixels, overlap 0.25.
  VaeTiling default_tiling() const;

  AutoencoderKLConfig config;
  VaeEncoder encoder{nullptr};
  VaeDecoder decoder{nullptr};
  Conv2d quant_conv{nullptr}, post_quant_conv{nullptr};
};
TORCH_MODULE(AutoencoderKL);

}  // namespace u3d::nn
