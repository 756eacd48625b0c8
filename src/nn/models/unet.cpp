#include "nn/models/unet.h"

#include <algorithm>
#include <utility>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"

namespace u3d::nn {

namespace {

template <class T>
std::vector<T> reversed(std::vector<T> v) {
  std::reverse(v.begin(), v.end());
  return v;
}

bool is_cross_attention_block(const std::string& type) { return type.rfind("CrossAttn", 0) == 0; }

}  // namespace

UNetConfig UNetConfig::from_json(const nlohmann::json& json, const std::string& source) {
  ConfigReader r(json, source);
  // Everything that would change the architecture or the math away from the SD 1.x family.
  r.require_value("act_fn", "silu");
  r.require_value("addition_embed_type", nullptr);
  r.require_value("class_embed_type", nullptr);
  r.require_value("class_embeddings_concat", false);
  r.require_value("center_input_sample", false);
  r.require_value("conv_in_kernel", 3);
  r.require_value("conv_out_kernel", 3);
  r.require_value("dual_cross_attention", false);
  r.require_value("encoder_hid_dim", nullptr);
  r.require_value("encoder_hid_dim_type", nullptr);
  r.require_value("mid_block_only_cross_attention", false);
  r.require_value("mid_block_scale_factor", 1);
  r.require_value("mid_block_type", "UNetMidBlock2DCrossAttn");
  r.require_value("only_cross_attention", false);
  r.require_value("resnet_out_scale_factor", 1);
  r.require_value("resnet_skip_time_act", false);
  r.require_value("resnet_time_scale_shift", "default");
  r.require_value("time_cond_proj_dim", nullptr);
  r.require_value("time_embedding_act_fn", nullptr);
  r.require_value("time_embedding_dim", nullptr);
  r.require_value("time_embedding_type", "positional");
  r.require_value("timestep_post_act", nullptr);
  r.require_value("upcast_attention", false);
  r.require_value("use_linear_projection", false);
  r.require_value("attention_type", "default");
  r.require_value("cross_attention_norm", nullptr);
  r.require_value("reverse_transformer_layers_per_block", nullptr);
  // diffusers itself rejects num_attention_heads for this model: "attention_head_dim" holds the heads.
  r.require_value("num_attention_heads", nullptr);

  UNetConfig c;
  c.in_channels = r.get_int("in_channels", 4);
  c.out_channels = r.get_int("out_channels", 4);
  c.block_out_channels = r.has("block_out_channels") ? r.get_int_list("block_out_channels")
                                                     : std::vector<int64_t>{320, 640, 1280, 1280};
  const size_t n = c.block_out_channels.size();
  c.down_block_types = r.has("down_block_types")
                           ? r.get_string_list("down_block_types")
                           : std::vector<std::string>{"CrossAttnDownBlock2D", "CrossAttnDownBlock2D",
                                                      "CrossAttnDownBlock2D", "DownBlock2D"};
  c.up_block_types = r.has("up_block_types") ? r.get_string_list("up_block_types")
                                             : std::vector<std::string>{"UpBlock2D", "CrossAttnUpBlock2D",
                                                                        "CrossAttnUpBlock2D", "CrossAttnUpBlock2D"};
  if (n == 0 || c.down_block_types.size() != n || c.up_block_types.size() != n)
    throw Error(source + ": block_out_channels, down_block_types and up_block_types must have the same, non-zero length");
  for (const auto& t : c.down_block_types)
    if (t != "CrossAttnDownBlock2D" && t != "DownBlock2D") r.unsupported("down_block_types", "unknown block " + t);
  for (const auto& t : c.up_block_types)
    if (t != "CrossAttnUpBlock2D" && t != "UpBlock2D") r.unsupported("up_block_types", "unknown block " + t);
  c.layers_per_block = r.get_int_or_list("layers_per_block", 2, n);
  c.attention_heads = r.get_int_or_list("attention_head_dim", 8, n);
  c.cross_attention_dim = r.get_int_or_list("cross_attention_dim", 1280, n);
  c.transformer_layers_per_block = r.get_int_or_list("transformer_layers_per_block", 1, n);
  c.norm_num_groups = r.get_int("norm_num_groups", 32);
  c.norm_eps = r.get_double("norm_eps", 1e-5);
  c.flip_sin_to_cos = r.get_bool("flip_sin_to_cos", true);
  c.freq_shift = r.get_double("freq_shift", 0);
  c.downsample_padding = r.get_int("downsample_padding", 1);
  c.num_class_embeds = r.get_int("num_class_embeds", 0);
  for (size_t i = 0; i < n; ++i)
    if (c.block_out_channels[i] % c.attention_heads[i] != 0 || c.block_out_channels[i] % c.norm_num_groups != 0)
      throw Error(source + ": block_out_channels[" + std::to_string(i) + "] = " + std::to_string(c.block_out_channels[i]) +
                  " does not divide into attention heads / norm groups");
  return c;
}

torch::Tensor batch_timesteps(const torch::Tensor& timestep, int64_t batch, const torch::Device& device) {
  torch::Tensor steps = timestep.to(device);
  if (steps.dim() == 0) steps = steps.unsqueeze(0);
  if (steps.dim() != 1 || (steps.size(0) != batch && steps.size(0) != 1))
    throw Error("UNet: " + std::to_string(steps.numel()) + " timesteps for a batch of " + std::to_string(batch));
  return steps.expand({batch});
}

UNetDownBlockImpl::UNetDownBlockImpl(const UNetConfig& c, size_t index, int64_t in_channels, int64_t temb_channels,
                                     const torch::TensorOptions& t) {
  const int64_t out = c.block_out_channels[index];
  const bool cross = is_cross_attention_block(c.down_block_types[index]);
  auto resnet_list = register_module("resnets", torch::nn::ModuleList());
  torch::nn::ModuleList attention_list;
  if (cross) attention_list = register_module("attentions", torch::nn::ModuleList());
  for (int64_t i = 0; i < c.layers_per_block[index]; ++i) {
    resnets.push_back(ResnetBlock2D(i == 0 ? in_channels : out, out, temb_channels, c.norm_num_groups, c.norm_eps, t));
    resnet_list->push_back(resnets.back());
    if (cross) {
      const int64_t heads = c.attention_heads[index];
      attentions.push_back(Transformer2DModel(heads, out / heads, out, c.transformer_layers_per_block[index],
                                              c.norm_num_groups, c.cross_attention_dim[index], t));
      attention_list->push_back(attentions.back());
    }
  }
  if (index + 1 < c.block_out_channels.size()) {
    downsampler = Downsample2D(out, c.downsample_padding, t);
    register_module("downsamplers", torch::nn::ModuleList(downsampler));
  }
}

torch::Tensor UNetDownBlockImpl::forward(torch::Tensor h, const torch::Tensor& temb,
                                         const torch::Tensor& encoder_hidden_states, std::vector<torch::Tensor>& skips) {
  for (size_t i = 0; i < resnets.size(); ++i) {
    h = resnets[i]->forward(h, temb);
    if (!attentions.empty()) h = attentions[i]->forward(h, encoder_hidden_states);
    skips.push_back(h);
  }
  if (downsampler) {
    h = downsampler->forward(h);
    skips.push_back(h);
  }
  return h;
}

UNetMidBlockImpl::UNetMidBlockImpl(const UNetConfig& c, int64_t temb_channels, const torch::TensorOptions& t) {
  const int64_t ch = c.block_out_channels.back();
  const int64_t heads = c.attention_heads.back();
  auto resnet_list = register_module("resnets", torch::nn::ModuleList());
  auto attention_list = register_module("attentions", torch::nn::ModuleList());
  for (int i = 0; i < 2; ++i) {
    resnets.push_back(ResnetBlock2D(ch, ch, temb_channels, c.norm_num_groups, c.norm_eps, t));
    resnet_list->push_back(resnets.back());
  }
  attentions.push_back(Transformer2DModel(heads, ch / heads, ch, c.transformer_layers_per_block.back(),
                                          c.norm_num_groups, c.cross_attention_dim.back(), t));
  attention_list->push_back(attentions.back());
}

torch::Tensor UNetMidBlockImpl::forward(torch::Tensor h, const torch::Tensor& temb,
                                        const torch::Tensor& encoder_hidden_states) {
  h = resnets[0]->forward(h, temb);
  for (size_t i = 0; i < attentions.size(); ++i) {
    h = attentions[i]->forward(h, encoder_hidden_states);
    h = resnets[i + 1]->forward(h, temb);
  }
  return h;
}

UNetUpBlockImpl::UNetUpBlockImpl(const UNetConfig& c, size_t index, int64_t temb_channels,
                                 const torch::TensorOptions& t) {
  // Channel bookkeeping as diffusers: the block's skips come from the mirrored down block, whose first
  // skip has the channel count of the block below it.
  const auto channels = reversed(c.block_out_channels);
  const size_t n = channels.size();
  const int64_t out = channels[index];
  const int64_t prev_output = channels[index == 0 ? 0 : index - 1];
  const int64_t skip_in = channels[std::min(index + 1, n - 1)];
  const int64_t layers = reversed(c.layers_per_block)[index] + 1;
  const int64_t heads = reversed(c.attention_heads)[index];
  const int64_t cross_dim = reversed(c.cross_attention_dim)[index];
  const int64_t transformer_layers = reversed(c.transformer_layers_per_block)[index];
  const bool cross = is_cross_attention_block(c.up_block_types[index]);

  auto resnet_list = register_module("resnets", torch::nn::ModuleList());
  torch::nn::ModuleList attention_list;
  if (cross) attention_list = register_module("attentions", torch::nn::ModuleList());
  for (int64_t i = 0; i < layers; ++i) {
    const int64_t skip_channels = i == layers - 1 ? skip_in : out;
    const int64_t resnet_in = i == 0 ? prev_output : out;
    resnets.push_back(ResnetBlock2D(resnet_in + skip_channels, out, temb_channels, c.norm_num_groups, c.norm_eps, t));
    resnet_list->push_back(resnets.back());
    if (cross) {
      attentions.push_back(Transformer2DModel(heads, out / heads, out, transformer_layers, c.norm_num_groups, cross_dim, t));
      attention_list->push_back(attentions.back());
    }
  }
  if (index + 1 < n) {
    upsampler = Upsample2D(out, t);
    register_module("upsamplers", torch::nn::ModuleList(upsampler));
  }
}

torch::Tensor UNetUpBlockImpl::forward(torch::Tensor h, const torch::Tensor& temb,
                                       const torch::Tensor& encoder_hidden_states, std::vector<torch::Tensor>& skips) {
  for (size_t i = 0; i < resnets.size(); ++i) {
    TORCH_CHECK(!skips.empty(), "UNet up block ran out of skip connections");
    // The hidden state and the skip are freed before the resnet runs: only their concatenation is kept.
    const torch::Tensor joined = torch::cat({h, skips.back()}, 1);
    skips.pop_back();
    h.reset();
    h = resnets[i]->forward(joined, temb);
    if (!attentions.empty()) h = attentions[i]->forward(h, encoder_hidden_states);
  }
  if (upsampler) {
    // Upsample to the size of the skip the next block concatenates (exactly x2 when the input size is
    // a multiple of the total downsampling factor, as required).
    TORCH_CHECK(!skips.empty(), "UNet up block ran out of skip connections");
    h = upsampler->forward(h, skips.back().sizes().slice(2));
  }
  return h;
}

UNet2DConditionModelImpl::UNet2DConditionModelImpl(const UNetConfig& c, const torch::TensorOptions& t) : config(c) {
  const int64_t c0 = c.block_out_channels[0];
  const int64_t temb = 4 * c0;
  conv_in = register_module("conv_in", Conv2d(c.in_channels, c0, 3, 1, 1, true, t));
  time_embedding = register_module("time_embedding", TimestepEmbedding(c0, temb, t));
  if (c.num_class_embeds > 0) class_embedding = register_module("class_embedding", Embedding(c.num_class_embeds, temb, t));

  auto down_list = register_module("down_blocks", torch::nn::ModuleList());
  int64_t in_channels = c0;
  for (size_t i = 0; i < c.block_out_channels.size(); ++i) {
    down_blocks.push_back(UNetDownBlock(c, i, in_channels, temb, t));
    down_list->push_back(down_blocks.back());
    in_channels = c.block_out_channels[i];
  }
  auto up_list = register_module("up_blocks", torch::nn::ModuleList());
  for (size_t i = 0; i < c.block_out_channels.size(); ++i) {
    up_blocks.push_back(UNetUpBlock(c, i, temb, t));
    up_list->push_back(up_blocks.back());
  }
  mid_block = register_module("mid_block", UNetMidBlock(c, temb, t));
  conv_norm_out = register_module("conv_norm_out", GroupNorm(c.norm_num_groups, c0, c.norm_eps, t));
  conv_out = register_module("conv_out", Conv2d(c0, c.out_channels, 3, 1, 1, true, t));
}

torch::Tensor UNet2DConditionModelImpl::forward(const torch::Tensor& sample, const torch::Tensor& timestep,
                                                const torch::Tensor& encoder_hidden_states, UNetExtras extras) {
  if (sample.dim() != 4) throw Error("UNet: sample must be [N, C, H, W], got " + c10::str(sample.sizes()));
  const int64_t batch = sample.size(0);
  const int64_t factor = int64_t{1} << (config.block_out_channels.size() - 1);
  torch::Tensor input = sample;
  if (extras.condition_latents.defined()) {
    const torch::Tensor& cond = extras.condition_latents;
    if (cond.dim() != 4 || cond.size(0) == 0 || batch % cond.size(0) != 0 ||
        cond.size(2) != sample.size(2) || cond.size(3) != sample.size(3))
      throw Error("UNet: condition_latents " + c10::str(cond.sizes()) + " do not fit the sample " + c10::str(sample.sizes()));
    const int64_t b = cond.size(0), c = cond.size(1);
    torch::Tensor repeated = cond.reshape({b, 1, c, cond.size(2), cond.size(3)})
                                 .repeat({1, batch / b, 1, 1, 1})
                                 .reshape({batch, c, cond.size(2), cond.size(3)});
    input = torch::cat({sample, repeated.to(sample.scalar_type())}, 1);
  }
  if (input.dim() != 4 || input.size(1) != config.in_channels || input.size(2) % factor || input.size(3) % factor)
    throw Error("UNet: the input (sample plus any condition latents) must be [N, " + std::to_string(config.in_channels) +
                ", H, W] with H, W multiples of " + std::to_string(factor) + ", got " + c10::str(input.sizes()));
  if (encoder_hidden_states.dim() != 3 || encoder_hidden_states.size(0) != batch)
    throw Error("UNet: encoder_hidden_states must be [" + std::to_string(batch) + ", L, C], got " +
                c10::str(encoder_hidden_states.sizes()));
  auto record = [&](const std::string& name, const torch::Tensor& value) {
    if (extras.trace) (*extras.trace)[name] = value;
  };
  // The model runs in the dtype of its weights (nn/precision.h); inputs are cast to it and the
  // output back to the sample's dtype.
  const torch::ScalarType compute = conv_in->weight.scalar_type();
  input = input.to(compute);
  const torch::Tensor context = encoder_hidden_states.to(compute);
  record("conv_in_input", input);

  torch::Tensor t_emb = timestep_projection(batch_timesteps(timestep, batch, sample.device()), config.block_out_channels[0], config.flip_sin_to_cos, config.freq_shift)
                            .to(compute);
  record("time_proj", t_emb);
  torch::Tensor emb = time_embedding->forward(t_emb);
  if (class_embedding) {
    if (!extras.class_labels.defined() || extras.class_labels.numel() != batch)
      throw Error("UNet: this model has a class embedding and needs " + std::to_string(batch) + " class labels");
    emb = emb + class_embedding->forward(extras.class_labels.to(sample.device()).reshape({batch})).to(emb.scalar_type());
  }
  record("time_embedding", emb);

  torch::Tensor h = conv_in->forward(input);
  record("conv_in", h);
  std::vector<torch::Tensor> skips{h};
  for (size_t i = 0; i < down_blocks.size(); ++i) {
    h = down_blocks[i]->forward(h, emb, context, skips);
    record("down_blocks." + std::to_string(i), h);
  }
  if (!extras.down_block_additional_residuals.empty()) {
    if (extras.down_block_additional_residuals.size() != skips.size())
      throw Error("UNet: " + std::to_string(extras.down_block_additional_residuals.size()) +
                  " down-block residuals given, the model has " + std::to_string(skips.size()) + " skip connections");
    for (size_t i = 0; i < skips.size(); ++i) skips[i] = skips[i] + extras.down_block_additional_residuals[i].to(compute);
    extras.down_block_additional_residuals.clear();
  }
  h = mid_block->forward(h, emb, context);
  if (extras.mid_block_additional_residual.defined()) h = h + extras.mid_block_additional_residual.to(compute);
  extras.mid_block_additional_residual.reset();
  record("mid_block", h);
  for (size_t i = 0; i < up_blocks.size(); ++i) {
    h = up_blocks[i]->forward(std::move(h), emb, context, skips);
    record("up_blocks." + std::to_string(i), h);
  }
  // contiguous(): bf16 convolutions work channels-last (nn/layers/onednn_conv.h); callers get NCHW.
  return conv_out->forward(conv_norm_out->forward_silu(h)).to(sample.scalar_type()).contiguous();
}

}  // namespace u3d::nn
