#include "nn/models/controlnet.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"

namespace u3d::nn {

ControlNetConfig ControlNetConfig::from_json(const nlohmann::json& json, const std::string& source) {
  ConfigReader r(json, source);
  r.require_value("controlnet_conditioning_channel_order", "rgb");
  r.require_value("global_pool_conditions", false);
  ControlNetConfig c;
  c.conditioning_channels = r.get_int("conditioning_channels", c.conditioning_channels);
  if (r.has("conditioning_embedding_out_channels"))
    c.conditioning_embedding_out_channels = r.get_int_list("conditioning_embedding_out_channels");
  if (c.conditioning_embedding_out_channels.empty())
    r.unsupported("conditioning_embedding_out_channels", "needs at least one entry");
  // The UNet reader checks the shared settings; a ControlNet config has no up blocks, so they are
  // filled in as the mirror of the down blocks to satisfy it.
  nlohmann::json unet_json = json;
  if (!r.has("up_block_types") && r.has("down_block_types")) {
    std::vector<std::string> up;
    for (const auto& type : r.get_string_list("down_block_types"))
      up.insert(up.begin(), type == "CrossAttnDownBlock2D" ? "CrossAttnUpBlock2D" : "UpBlock2D");
    unet_json["up_block_types"] = up;
  }
  c.unet = UNetConfig::from_json(unet_json, source);
  return c;
}

ControlNetConditioningEmbeddingImpl::ControlNetConditioningEmbeddingImpl(int64_t out_channels,
                                                                         const std::vector<int64_t>& channels,
                                                                         int64_t conditioning_channels,
                                                                         const torch::TensorOptions& t) {
  conv_in = register_module("conv_in", Conv2d(conditioning_channels, channels[0], 3, 1, 1, true, t));
  auto list = register_module("blocks", torch::nn::ModuleList());
  for (size_t i = 0; i + 1 < channels.size(); ++i) {
    blocks.push_back(Conv2d(channels[i], channels[i], 3, 1, 1, true, t));
    blocks.push_back(Conv2d(channels[i], channels[i + 1], 3, 2, 1, true, t));
  }
  for (auto& b : blocks) list->push_back(b);
  conv_out = register_module("conv_out", Conv2d(channels.back(), out_channels, 3, 1, 1, true, t));
}

torch::Tensor ControlNetConditioningEmbeddingImpl::forward(const torch::Tensor& condition) {
  torch::Tensor h = conv_in->forward(condition);
  torch::silu_(h);
  for (auto& b : blocks) {
    h = b->forward(h);
    torch::silu_(h);
  }
  return conv_out->forward(h);
}

ControlNetModelImpl::ControlNetModelImpl(const ControlNetConfig& c, const torch::TensorOptions& t) : config(c) {
  const UNetConfig& u = c.unet;
  const int64_t c0 = u.block_out_channels[0];
  const int64_t temb = 4 * c0;
  conv_in = register_module("conv_in", Conv2d(u.in_channels, c0, 3, 1, 1, true, t));
  time_embedding = register_module("time_embedding", TimestepEmbedding(c0, temb, t));
  controlnet_cond_embedding = register_module(
      "controlnet_cond_embedding",
      ControlNetConditioningEmbedding(c0, c.conditioning_embedding_out_channels, c.conditioning_channels, t));

  auto down_list = register_module("down_blocks", torch::nn::ModuleList());
  auto zero_list = register_module("controlnet_down_blocks", torch::nn::ModuleList());
  auto zero_conv = [&](int64_t channels) {
    controlnet_down_blocks.push_back(Conv2d(channels, channels, 1, 1, 0, true, t));
    zero_list->push_back(controlnet_down_blocks.back());
  };
  zero_conv(c0);  // for the conv_in output
  int64_t in_channels = c0;
  for (size_t i = 0; i < u.block_out_channels.size(); ++i) {
    down_blocks.push_back(UNetDownBlock(u, i, in_channels, temb, t));
    down_list->push_back(down_blocks.back());
    in_channels = u.block_out_channels[i];
    for (int64_t layer = 0; layer < u.layers_per_block[i]; ++layer) zero_conv(in_channels);
    if (i + 1 < u.block_out_channels.size()) zero_conv(in_channels);  // after the downsampler
  }
  const int64_t mid = u.block_out_channels.back();
  controlnet_mid_block = register_module("controlnet_mid_block", Conv2d(mid, mid, 1, 1, 0, true, t));
  mid_block = register_module("mid_block", UNetMidBlock(u, temb, t));
}

namespace {

void check_sample(const UNetConfig& u, const torch::Tensor& sample) {
  const int64_t factor = int64_t{1} << (u.block_out_channels.size() - 1);
  if (sample.dim() != 4 || sample.size(1) != u.in_channels || sample.size(2) % factor || sample.size(3) % factor)
    throw Error("ControlNet: sample must be [N, " + std::to_string(u.in_channels) + ", h, w] with h, w multiples of " +
                std::to_string(factor) + ", got " + c10::str(sample.sizes()));
}

}  // namespace

torch::Tensor ControlNetModelImpl::embed_condition(const torch::Tensor& controlnet_cond) {
  const int64_t cond_factor = int64_t{1} << (config.conditioning_embedding_out_channels.size() - 1);
  if (controlnet_cond.dim() != 4 || controlnet_cond.size(1) != config.conditioning_channels ||
      controlnet_cond.size(2) % cond_factor || controlnet_cond.size(3) % cond_factor)
    throw Error("ControlNet: the control image must be [N, " + std::to_string(config.conditioning_channels) +
                ", H, W] with H, W multiples of " + std::to_string(cond_factor) + ", got " +
                c10::str(controlnet_cond.sizes()));
  return controlnet_cond_embedding->forward(controlnet_cond.to(conv_in->weight.scalar_type()));
}

ControlNetOutput ControlNetModelImpl::forward(const torch::Tensor& sample, const torch::Tensor& timestep,
                                              const torch::Tensor& encoder_hidden_states,
                                              const torch::Tensor& controlnet_cond, double conditioning_scale) {
  check_sample(config.unet, sample);
  const int64_t batch = sample.size(0);
  const int64_t cond_factor = int64_t{1} << (config.conditioning_embedding_out_channels.size() - 1);
  if (controlnet_cond.dim() != 4 || controlnet_cond.size(0) != batch ||
      controlnet_cond.size(1) != config.conditioning_channels || controlnet_cond.size(2) != sample.size(2) * cond_factor ||
      controlnet_cond.size(3) != sample.size(3) * cond_factor)
    throw Error("ControlNet: the control image must be [" + std::to_string(batch) + ", " +
                std::to_string(config.conditioning_channels) + ", " + std::to_string(sample.size(2) * cond_factor) + ", " +
                std::to_string(sample.size(3) * cond_factor) + "], got " + c10::str(controlnet_cond.sizes()));
  return forward_embedded(sample, timestep, encoder_hidden_states, embed_condition(controlnet_cond), conditioning_scale);
}

ControlNetOutput ControlNetModelImpl::forward_embedded(const torch::Tensor& sample, const torch::Tensor& timestep,
                                                       const torch::Tensor& encoder_hidden_states,
                                                       const torch::Tensor& embedded_cond, double conditioning_scale) {
  const UNetConfig& u = config.unet;
  check_sample(u, sample);
  const int64_t batch = sample.size(0);
  if (embedded_cond.dim() != 4 || embedded_cond.size(0) != batch ||
      embedded_cond.size(1) != u.block_out_channels[0] || embedded_cond.size(2) != sample.size(2) ||
      embedded_cond.size(3) != sample.size(3))
    throw Error("ControlNet: the embedded control image must be [" + std::to_string(batch) + ", " +
                std::to_string(u.block_out_channels[0]) + ", " + std::to_string(sample.size(2)) + ", " +
                std::to_string(sample.size(3)) + "] (embed_condition), got " + c10::str(embedded_cond.sizes()));
  if (encoder_hidden_states.dim() != 3 || encoder_hidden_states.size(0) != batch)
    throw Error("ControlNet: encoder_hidden_states must be [" + std::to_string(batch) + ", L, C], got " +
                c10::str(encoder_hidden_states.sizes()));
  // Runs in the dtype of its weights (nn/precision.h); the residuals come back in the sample's dtype.
  const torch::ScalarType compute = conv_in->weight.scalar_type();
  const torch::Tensor context = encoder_hidden_states.to(compute);
  const torch::Tensor t_emb =
      timestep_projection(batch_timesteps(timestep, batch, sample.device()), u.block_out_channels[0], u.flip_sin_to_cos,
                          u.freq_shift)
          .to(compute);
  const torch::Tensor emb = time_embedding->forward(t_emb);

  torch::Tensor h = conv_in->forward(sample.to(compute)) + embedded_cond.to(compute);
  std::vector<torch::Tensor> skips{h};
  for (auto& block : down_blocks) h = block->forward(h, emb, context, skips);
  h = mid_block->forward(h, emb, context);

  ControlNetOutput out;
  for (size_t i = 0; i < skips.size(); ++i)
    out.down_block_res_samples.push_back(
        (controlnet_down_blocks[i]->forward(skips[i]) * conditioning_scale).to(sample.scalar_type()));
  out.mid_block_res_sample = (controlnet_mid_block->forward(h) * conditioning_scale).to(sample.scalar_type());
  return out;
}

}  // namespace u3d::nn
