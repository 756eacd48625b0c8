#pragma once
// diffusers UNet2DConditionModel in the SD 1.x layouts (CrossAttnDownBlock2D / DownBlock2D,
// UNetMidBlock2DCrossAttn, UpBlock2D / CrossAttnUpBlock2D), built from its config.json, with parameter
// names equal to diffusers' state-dict keys. Also covers Unique3D's variants: class embedding added to
// the time embedding (num_class_embeds), more conv_in channels (cat_condition: the caller concatenates)
// and multi-view attn1 (the caller sets a MultiViewAttentionProcessor on it, nn/layers/multiview_attention.h).
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <torch/torch.h>
#include <vector>

#include "nn/checkpoint/tensor_map.h"
#include "nn/layers/layers.h"
#include "nn/layers/transformer_2d.h"
#include "nn/layers/unet_blocks.h"

namespace u3d::nn {

struct UNetConfig {
  int64_t in_channels = 4;
  int64_t out_channels = 4;
  std::vector<int64_t> block_out_channels;
  std::vector<std::string> down_block_types;  // CrossAttnDownBlock2D | DownBlock2D
  std::vector<std::string> up_block_types;    // UpBlock2D | CrossAttnUpBlock2D
  std::vector<int64_t> layers_per_block;      // per down block
  std::vector<int64_t> attention_heads;       // per down block (diffusers' "attention_head_dim" = heads)
  std::vector<int64_t> cross_attention_dim;   // per down block
  std::vector<int64_t> transformer_layers_per_block;  // per down block
  int64_t norm_num_groups = 32;
  double norm_eps = 1e-5;
  bool flip_sin_to_cos = true;
  double freq_shift = 0;
  int64_t downsample_padding = 1;
  int64_t num_class_embeds = 0;  // 0: no class embedding

  // Reads a diffusers unet config.json object; settings outside the SD 1.x family are an Error naming
  // `source` and the key.
  static UNetConfig from_json(const nlohmann::json& json, const std::string& source);
};

// Optional inputs of UNet2DConditionModel::forward.
struct UNetExtras {
  torch::Tensor class_labels;  // [N] int64; required iff the config has num_class_embeds
  // Unique3D cat_condition: [B, C, H, W] latents with N a multiple of B; each is repeated for its N/B
  // consecutive samples and concatenated after the noisy latents on channels, before conv_in.
  torch::Tensor condition_latents;
  std::vector<torch::Tensor> down_block_additional_residuals;  // ControlNet: added to every skip
  torch::Tensor mid_block_additional_residual;                 // ControlNet: added after the mid block
  // When set, receives intermediate tensors: conv_in_input, time_proj, time_embedding, conv_in, down_blocks.<i>,
  // mid_block, up_blocks.<i> (the hidden state leaving each).
  TensorMap* trace = nullptr;
};

// The UNet's timestep input for a batch: a 0-dim or [1] value is expanded to `batch`, [batch] is kept;
// anything else is an Error.
torch::Tensor batch_timesteps(const torch::Tensor& timestep, int64_t batch, const torch::Device& device);

class UNetDownBlockImpl : public torch::nn::Module {
 public:
  UNetDownBlockImpl(const UNetConfig& config, size_t index, int64_t in_channels, int64_t temb_channels,
                    const torch::TensorOptions& options);
  // Appends the hidden state after every resnet(+attention) and after the downsampler to `skips`.
  torch::Tensor forward(torch::Tensor h, const torch::Tensor& temb, const torch::Tensor& encoder_hidden_states,
                        std::vector<torch::Tensor>& skips);
  std::vector<ResnetBlock2D> resnets;
  std::vector<Transformer2DModel> attentions;
  Downsample2D downsampler{nullptr};
};
TORCH_MODULE(UNetDownBlock);

class UNetMidBlockImpl : public torch::nn::Module {
 public:
  UNetMidBlockImpl(const UNetConfig& config, int64_t temb_channels, const torch::TensorOptions& options);
  torch::Tensor forward(torch::Tensor h, const torch::Tensor& temb, const torch::Tensor& encoder_hidden_states);
  std::vector<ResnetBlock2D> resnets;
  std::vector<Transformer2DModel> attentions;
};
TORCH_MODULE(UNetMidBlock);

class UNetUpBlockImpl : public torch::nn::Module {
 public:
  // index: position in up_block_types (0 = deepest).
  UNetUpBlockImpl(const UNetConfig& config, size_t index, int64_t temb_channels, const torch::TensorOptions& options);
  // Consumes skips from the back, concatenating [h, skip] on channels before each resnet.
  torch::Tensor forward(torch::Tensor h, const torch::Tensor& temb, const torch::Tensor& encoder_hidden_states,
                        std::vector<torch::Tensor>& skips);
  std::vector<ResnetBlock2D> resnets;
  std::vector<Transformer2DModel> attentions;
  Upsample2D upsampler{nullptr};
};
TORCH_MODULE(UNetUpBlock);

class UNet2DConditionModelImpl : public torch::nn::Module {
 public:
  UNet2DConditionModelImpl(const UNetConfig& config, const torch::TensorOptions& options);

  // sample [N, in_channels, H, W] ([N, in_channels - C, H, W] with condition_latents); timestep 0-dim or [N] (float or integer; a 0-dim or [1] value
  // applies to the whole batch); encoder_hidden_states [N, L, cross_attention_dim]. H and W must be
  // multiples of 2^(number of downsamplers). Returns [N, out_channels, H, W]. `extras` is taken by
  // value: the ControlNet residuals are dropped once added to the skips, so a caller that moves them in
  // does not hold them through the up blocks (212 MB at batch 2 on a 1024 px image in fp32).
  torch::Tensor forward(const torch::Tensor& sample, const torch::Tensor& timestep,
                        const torch::Tensor& encoder_hidden_states, UNetExtras extras = {});

  UNetConfig config;
  Conv2d conv_in{nullptr}, conv_out{nullptr};
  TimestepEmbedding time_embedding{nullptr};
  Embedding class_embedding{nullptr};
  std::vector<UNetDownBlock> down_blocks;
  UNetMidBlock mid_block{nullptr};
  std::vector<UNetUpBlock> up_blocks;
  GroupNorm conv_norm_out{nullptr};
};
TORCH_MODULE(UNet2DConditionModel);

}  // namespace u3d::nn
