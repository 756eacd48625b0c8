#include "nn/models/vae.h"

#include <algorithm>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"

namespace u3d::nn {

namespace {
constexpr double kVaeNormEps = 1e-6;  // every GroupNorm of the VAE
}

AutoencoderKLConfig AutoencoderKLConfig::from_json(const nlohmann::json& json, const std::string& source) {
  ConfigReader r(json, source);
  r.require_value("act_fn", "silu");
  r.require_value("mid_block_add_attention", true);
  r.require_value("use_quant_conv", true);
  r.require_value("use_post_quant_conv", true);
  AutoencoderKLConfig c;
  c.in_channels = r.get_int("in_channels", 3);
  c.out_channels = r.get_int("out_channels", 3);
  c.block_out_channels = r.has("block_out_channels") ? r.get_int_list("block_out_channels") : std::vector<int64_t>{64};
  const size_t n = c.block_out_channels.size();
  const auto down = r.has("down_block_types") ? r.get_string_list("down_block_types")
                                              : std::vector<std::string>{"DownEncoderBlock2D"};
  const auto up =
      r.has("up_block_types") ? r.get_string_list("up_block_types") : std::vector<std::string>{"UpDecoderBlock2D"};
  if (n == 0 || down.size() != n || up.size() != n)
    throw Error(source + ": block_out_channels, down_block_types and up_block_types must have the same, non-zero length");
  for (const auto& t : down)
    if (t != "DownEncoderBlock2D") r.unsupported("down_block_types", "unknown block " + t);
  for (const auto& t : up)
    if (t != "UpDecoderBlock2D") r.unsupported("up_block_types", "unknown block " + t);
  c.layers_per_block = r.get_int("layers_per_block", 1);
  c.latent_channels = r.get_int("latent_channels", 4);
  c.norm_num_groups = r.get_int("norm_num_groups", 32);
  c.scaling_factor = r.get_double("scaling_factor", 0.18215);
  if (r.has("sample_size") && json.at("sample_size").is_array()) {  // [h, w]: diffusers tiles by the first
    const auto sizes = r.get_int_list("sample_size");
    if (sizes.empty()) r.unsupported("sample_size", "an empty list");
    c.sample_size = sizes.front();
  } else {
    c.sample_size = r.get_int("sample_size", 32);
  }
  if (c.sample_size < c.scale_factor()) r.unsupported("sample_size", "smaller than one latent pixel");
  return c;
}

void convert_legacy_vae_attention_keys(TensorMap& state_dict) {
  static const std::pair<const char*, const char*> kRenames[] = {
      {"query", "to_q"}, {"key", "to_k"}, {"value", "to_v"}, {"proj_attn", "to_out.0"}};
  TensorMap converted;
  for (auto& [name, tensor] : state_dict) {
    std::string renamed = name;
    const std::string marker = "mid_block.attentions.0.";
    const auto pos = name.find(marker);
    if (pos != std::string::npos) {
      const std::string rest = name.substr(pos + marker.size());  // e.g. "query.weight"
      for (const auto& [old_name, new_name] : kRenames) {
        const std::string prefix = std::string(old_name) + ".";
        if (rest.rfind(prefix, 0) == 0) renamed = name.substr(0, pos + marker.size()) + new_name + "." + rest.substr(prefix.size());
      }
    }
    converted.emplace(renamed, tensor);
  }
  state_dict = std::move(converted);
}

VaeMidBlockImpl::VaeMidBlockImpl(int64_t channels, int64_t groups, const torch::TensorOptions& t) {
  AttentionOptions a;
  a.query_dim = channels;
  a.heads = 1;
  a.dim_head = channels;
  a.qkv_bias = true;
  a.norm_groups = groups;
  a.norm_eps = kVaeNormEps;
  a.residual_connection = true;
  attention = Attention(a, t);
  register_module("attentions", torch::nn::ModuleList(attention));
  auto resnet_list = register_module("resnets", torch::nn::ModuleList());
  for (int i = 0; i < 2; ++i) {
    resnets.push_back(ResnetBlock2D(channels, channels, 0, groups, kVaeNormEps, t));
    resnet_list->push_back(resnets.back());
  }
}

torch::Tensor VaeMidBlockImpl::forward(torch::Tensor h) {
  h = resnets[0]->forward(h);
  h = attention->forward(h);
  return resnets[1]->forward(h);
}

VaeBlockImpl::VaeBlockImpl(Kind kind, int64_t in_channels, int64_t out_channels, int64_t layers, bool resample,
                           int64_t groups, const torch::TensorOptions& t) {
  auto resnet_list = register_module("resnets", torch::nn::ModuleList());
  for (int64_t i = 0; i < layers; ++i) {
    resnets.push_back(ResnetBlock2D(i == 0 ? in_channels : out_channels, out_channels, 0, groups, kVaeNormEps, t));
    resnet_list->push_back(resnets.back());
  }
  if (!resample) return;
  if (kind == Kind::Down) {
    downsampler = Downsample2D(out_channels, 0, t);
    register_module("downsamplers", torch::nn::ModuleList(downsampler));
  } else {
    upsampler = Upsample2D(out_channels, t);
    register_module("upsamplers", torch::nn::ModuleList(upsampler));
  }
}

torch::Tensor VaeBlockImpl::forward(torch::Tensor h) {
  for (auto& r : resnets) h = r->forward(h);
  if (downsampler) h = downsampler->forward(h);
  if (upsampler) h = upsampler->forward(h);
  return h;
}

VaeEncoderImpl::VaeEncoderImpl(const AutoencoderKLConfig& c, const torch::TensorOptions& t) {
  const auto& ch = c.block_out_channels;
  conv_in = register_module("conv_in", Conv2d(c.in_channels, ch[0], 3, 1, 1, true, t));
  auto list = register_module("down_blocks", torch::nn::ModuleList());
  for (size_t i = 0; i < ch.size(); ++i) {
    down_blocks.push_back(VaeBlock(VaeBlockImpl::Kind::Down, ch[i == 0 ? 0 : i - 1], ch[i], c.layers_per_block,
                                   i + 1 < ch.size(), c.norm_num_groups, t));
    list->push_back(down_blocks.back());
  }
  mid_block = register_module("mid_block", VaeMidBlock(ch.back(), c.norm_num_groups, t));
  conv_norm_out = register_module("conv_norm_out", GroupNorm(c.norm_num_groups, ch.back(), kVaeNormEps, t));
  conv_out = register_module("conv_out", Conv2d(ch.back(), 2 * c.latent_channels, 3, 1, 1, true, t));
}

torch::Tensor VaeEncoderImpl::forward(const torch::Tensor& image) {
  torch::Tensor h = conv_in->forward(image);
  for (auto& b : down_blocks) h = b->forward(h);
  h = mid_block->forward(h);
  return conv_out->forward(conv_norm_out->forward_silu(h));
}

VaeDecoderImpl::VaeDecoderImpl(const AutoencoderKLConfig& c, const torch::TensorOptions& t) {
  std::vector<int64_t> ch(c.block_out_channels.rbegin(), c.block_out_channels.rend());
  conv_in = register_module("conv_in", Conv2d(c.latent_channels, ch[0], 3, 1, 1, true, t));
  mid_block = register_module("mid_block", VaeMidBlock(ch[0], c.norm_num_groups, t));
  auto list = register_module("up_blocks", torch::nn::ModuleList());
  for (size_t i = 0; i < ch.size(); ++i) {
    up_blocks.push_back(VaeBlock(VaeBlockImpl::Kind::Up, ch[i == 0 ? 0 : i - 1], ch[i], c.layers_per_block + 1,
                                 i + 1 < ch.size(), c.norm_num_groups, t));
    list->push_back(up_blocks.back());
  }
  conv_norm_out = register_module("conv_norm_out", GroupNorm(c.norm_num_groups, ch.back(), kVaeNormEps, t));
  conv_out = register_module("conv_out", Conv2d(ch.back(), c.out_channels, 3, 1, 1, true, t));
}

torch::Tensor VaeDecoderImpl::forward(const torch::Tensor& latent) {
  torch::Tensor h = conv_in->forward(latent);
  h = mid_block->forward(h);
  for (auto& b : up_blocks) h = b->forward(h);
  return conv_out->forward(conv_norm_out->forward_silu(h));
}

namespace {

// Cross-fades the start of `tile` along `dim` from the end of its already blended neighbour `before`:
// over the shared band of e pixels the weight of `tile` rises linearly 0, 1/e, ..., (e-1)/e.
void blend_into(const torch::Tensor& before, torch::Tensor& tile, int64_t dim, int64_t band) {
  const int64_t e = std::min({before.size(dim), tile.size(dim), band});
  if (e <= 0) return;
  std::vector<int64_t> shape(tile.dim(), 1);
  shape[dim] = e;
  const torch::Tensor ramp = (torch::arange(e, tile.options()) / static_cast<double>(e)).reshape(shape);
  torch::Tensor head = tile.narrow(dim, 0, e);
  head.copy_(before.narrow(dim, before.size(dim) - e, e) * (1.0 - ramp) + head * ramp);
}

}  // namespace

torch::Tensor decode_in_tiles(const torch::Tensor& latent, const VaeTiling& tiling, int64_t scale,
                              const std::function<torch::Tensor(const torch::Tensor&)>& decode_tile) {
  const int64_t tile = tiling.tile_latent;
  if (tile < 1 || !(tiling.overlap >= 0.0 && tiling.overlap <= 0.5) || scale < 1)
    throw Error("VAE tiled decode: tile_latent must be >= 1 and overlap in [0, 0.5], got tile " +
                std::to_string(tile) + ", overlap " + std::to_string(tiling.overlap));
  if (latent.dim() != 4) throw Error("VAE tiled decode: latent must be [N, C, h, w], got " + c10::str(latent.sizes()));
  const int64_t h = latent.size(2), w = latent.size(3);
  if (h <= tile && w <= tile) return decode_tile(latent);
  // Truncated as diffusers does; the kept part of a tile is exactly one stride of image pixels, and the
  // rest of it is the band the next tile blends over. overlap <= 0.5 keeps a tile's two bands disjoint.
  const int64_t stride = std::max<int64_t>(1, static_cast<int64_t>(tile * (1.0 - tiling.overlap)));
  const int64_t keep = stride * scale, band = (tile - stride) * scale;

  std::vector<torch::Tensor> rows, above;  // `above`: the blended, uncropped tiles of the previous row
  for (int64_t y = 0; y < h; y += stride) {
    std::vector<torch::Tensor> current, kept;
    for (int64_t x = 0; x < w; x += stride) {
      torch::Tensor t = decode_tile(latent.narrow(2, y, std::min(tile, h - y)).narrow(3, x, std::min(tile, w - x)));
      if (!above.empty()) blend_into(above[current.size()], t, 2, band);
      if (!current.empty()) blend_into(current.back(), t, 3, band);
      kept.push_back(t.narrow(2, 0, std::min(keep, t.size(2))).narrow(3, 0, std::min(keep, t.size(3))));
      current.push_back(t);
    }
    rows.push_back(torch::cat(kept, 3));
    above = std::move(current);
  }
  return torch::cat(rows, 2);
}

AutoencoderKLImpl::AutoencoderKLImpl(const AutoencoderKLConfig& c, const torch::TensorOptions& t) : config(c) {
  encoder = register_module("encoder", VaeEncoder(c, t));
  decoder = register_module("decoder", VaeDecoder(c, t));
  quant_conv = register_module("quant_conv", Conv2d(2 * c.latent_channels, 2 * c.latent_channels, 1, 1, 0, true, t));
  post_quant_conv = register_module("post_quant_conv", Conv2d(c.latent_channels, c.latent_channels, 1, 1, 0, true, t));
}

LatentDistribution AutoencoderKLImpl::encode(const torch::Tensor& image) {
  const int64_t factor = config.scale_factor();
  if (image.dim() != 4 || image.size(1) != config.in_channels || image.size(2) % factor || image.size(3) % factor)
    throw Error("VAE encode: image must be [N, " + std::to_string(config.in_channels) + ", H, W] with H, W multiples of " +
                std::to_string(factor) + ", got " + c10::str(image.sizes()));
  // Runs in the dtype of its weights (nn/precision.h); returns the image's dtype.
  auto moments = quant_conv->forward(encoder->forward(image.to(quant_conv->weight.scalar_type())))
                     .to(image.scalar_type())
                     .contiguous()  // NCHW for the caller (bf16 convolutions work channels-last)
                     .chunk(2, 1);
  return {moments[0], moments[1].clamp(-30.0, 20.0)};
}

torch::Tensor AutoencoderKLImpl::decode(const torch::Tensor& latent) {
  if (latent.dim() != 4 || latent.size(1) != config.latent_channels)
    throw Error("VAE decode: latent must be [N, " + std::to_string(config.latent_channels) + ", h, w], got " +
                c10::str(latent.sizes()));
  return decoder->forward(post_quant_conv->forward(latent.to(post_quant_conv->weight.scalar_type())))
      .to(latent.scalar_type())
      .contiguous();
}

torch::Tensor AutoencoderKLImpl::decode_tiled(const torch::Tensor& latent, const VaeTiling& tiling) {
  return decode_in_tiles(latent, tiling, config.scale_factor(), [this](const torch::Tensor& t) { return decode(t); });
}

VaeTiling AutoencoderKLImpl::default_tiling() const {
  return VaeTiling{config.sample_size / config.scale_factor(), 0.25};
}

}  // namespace u3d::nn
