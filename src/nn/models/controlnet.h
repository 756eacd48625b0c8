#pragma once
// diffusers ControlNetModel for SD 1.x (e.g. ControlNet-tile, lllyasviel/control_v11f1e_sd15_tile): the
// UNet's conv_in, time embedding, down blocks and mid block (nn/models/unet.h), plus the conditioning
// embedding (a small strided conv stack from the control image to the conv_in features, added to them)
// and one 1x1 "zero" convolution per skip connection and after the mid block. Its outputs are the
// residuals UNet2DConditionModel::forward adds through UNetExtras. Parameter names are diffusers'.
#include <nlohmann/json.hpp>
#include <string>
#include <torch/torch.h>
#include <vector>

#include "nn/layers/layers.h"
#include "nn/models/unet.h"

namespace u3d::nn {

struct ControlNetConfig {
  UNetConfig unet;  // the down/mid part (up_block_types are not used)
  int64_t conditioning_channels = 3;
  std::vector<int64_t> conditioning_embedding_out_channels{16, 32, 96, 256};

  // Reads a diffusers controlnet config.json; settings outside the SD 1.x family (BGR conditioning,
  // global pooling of the conditions, ...) are an Error naming `source` and the key.
  static ControlNetConfig from_json(const nlohmann::json& json, const std::string& source);
};

// ControlNetConditioningEmbedding: conv_in -> SiLU -> pairs of (3x3 conv, 3x3 stride-2 conv), each
// followed by SiLU -> conv_out (no activation). The control image is 2^(pairs) times the latent size.
class ControlNetConditioningEmbeddingImpl : public torch::nn::Module {
 public:
  ControlNetConditioningEmbeddingImpl(int64_t out_channels, const std::vector<int64_t>& block_out_channels,
                                      int64_t conditioning_channels, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& condition);
  Conv2d conv_in{nullptr}, conv_out{nullptr};
  std::vector<Conv2d> blocks;
};
TORCH_MODULE(ControlNetConditioningEmbedding);

struct ControlNetOutput {
  std::vector<torch::Tensor> down_block_res_samples;  // one per UNet skip connection, conv_in output first
  torch::Tensor mid_block_res_sample;
};

class ControlNetModelImpl : public torch::nn::Module {
 public:
  ControlNetModelImpl(const ControlNetConfig& config, const torch::TensorOptions& options);

  // sample [N, 4, h, w] as the UNet's; timestep 0-dim or [N]; encoder_hidden_states [N, L, cross dim];
  // controlnet_cond [N, 3, h*f, w*f] RGB in [0, 1] (f = 2^(conditioning blocks - 1), 8 for SD 1.5). The
  // residuals are multiplied by conditioning_scale and returned in the sample's dtype.
  ControlNetOutput forward(const torch::Tensor& sample, const torch::Tensor& timestep,
                           const torch::Tensor& encoder_hidden_states, const torch::Tensor& controlnet_cond,
                           double conditioning_scale = 1.0);

  // forward() in two parts. embed_condition: the control image [N, 3, h*f, w*f] through
  // controlnet_cond_embedding, in the model's dtype, [N, C, h, w]; it depends on nothing else, so a
  // control image that stays the same over a pipeline's steps is embedded once. forward_embedded: the
  // rest, with the embedding of the batch's control images. (Not one image's embedding for a whole
  // batch: in fp32 the convolutions round differently at another batch size.)
  torch::Tensor embed_condition(const torch::Tensor& controlnet_cond);
  ControlNetOutput forward_embedded(const torch::Tensor& sample, const torch::Tensor& timestep,
                                    const torch::Tensor& encoder_hidden_states, const torch::Tensor& embedded_cond,
                                    double conditioning_scale = 1.0);

  ControlNetConfig config;
  Conv2d conv_in{nullptr};
  TimestepEmbedding time_embedding{nullptr};
  ControlNetConditioningEmbedding controlnet_cond_embedding{nullptr};
  std::vector<UNetDownBlock> down_blocks;
  std::vector<Conv2d> controlnet_down_blocks;
  Conv2d controlnet_mid_block{nullptr};
  UNetMidBlock mid_block{nullptr};
};
TORCH_MODULE(ControlNetModel);

}  // namespace u3d::nn
