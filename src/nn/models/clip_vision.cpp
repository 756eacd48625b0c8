#include "nn/models/clip_vision.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"

namespace u3d::nn {

ClipVisionConfig ClipVisionConfig::from_json(const nlohmann::json& json, const std::string& source) {
  if (json.is_object() && json.contains("vision_config") && json.at("vision_config").is_object()) {
    ClipVisionConfig c = from_json(json.at("vision_config"), source + " (vision_config)");
    // In a full CLIPConfig the projection size lives at the top level.
    c.projection_dim = ConfigReader(json, source).get_int("projection_dim", c.projection_dim);
    return c;
  }
  ConfigReader r(json, source);
  ClipVisionConfig c;
  c.hidden_size = r.get_int("hidden_size", c.hidden_size);
  c.intermediate_size = r.get_int("intermediate_size", c.intermediate_size);
  c.num_hidden_layers = r.get_int("num_hidden_layers", c.num_hidden_layers);
  c.num_attention_heads = r.get_int("num_attention_heads", c.num_attention_heads);
  c.num_channels = r.get_int("num_channels", c.num_channels);
  c.image_size = r.get_int("image_size", c.image_size);
  c.patch_size = r.get_int("patch_size", c.patch_size);
  c.projection_dim = r.get_int("projection_dim", c.projection_dim);
  c.layer_norm_eps = r.get_double("layer_norm_eps", c.layer_norm_eps);
  c.hidden_act = parse_clip_activation(r.get_string("hidden_act", "quick_gelu"), source);
  if (c.hidden_size % c.num_attention_heads != 0)
    throw Error(source + ": hidden_size " + std::to_string(c.hidden_size) + " is not divisible by num_attention_heads " +
                std::to_string(c.num_attention_heads));
  if (c.patch_size <= 0 || c.image_size % c.patch_size != 0)
    throw Error(source + ": image_size " + std::to_string(c.image_size) + " is not a multiple of patch_size " +
                std::to_string(c.patch_size));
  return c;
}

void drop_clip_vision_position_ids(TensorMap& state_dict) { state_dict.erase("vision_model.embeddings.position_ids"); }

ClipVisionEmbeddingsImpl::ClipVisionEmbeddingsImpl(const ClipVisionConfig& c, const torch::TensorOptions& t) {
  class_embedding = register_parameter("class_embedding", torch::empty({c.hidden_size}, t), false);
  patch_embedding = register_module("patch_embedding",
                                    Conv2d(c.num_channels, c.hidden_size, c.patch_size, c.patch_size, 0, false, t));
  const int64_t patches_per_side = c.image_size / c.patch_size;
  position_embedding = register_module("position_embedding",
                                       Embedding(patches_per_side * patches_per_side + 1, c.hidden_size, t));
}

torch::Tensor ClipVisionEmbeddingsImpl::forward(const torch::Tensor& pixel_values) {
  const int64_t n = pixel_values.size(0);
  torch::Tensor patches = patch_embedding->forward(pixel_values.to(patch_embedding->weight.scalar_type()));
  patches = patches.flatten(2).transpose(1, 2);  // [N, patches, hidden]
  torch::Tensor cls = class_embedding.reshape({1, 1, -1}).expand({n, 1, -1});
  return torch::cat({cls, patches}, 1) + position_embedding->weight.unsqueeze(0);
}

ClipVisionModelWithProjectionImpl::ClipVisionModelWithProjectionImpl(const ClipVisionConfig& c,
                                                                     const torch::TensorOptions& t)
    : config(c) {
  // transformers nests the ViT under "vision_model"; a plain Module gives the same key prefixes.
  auto vision_model = register_module("vision_model", std::make_shared<torch::nn::Module>());
  embeddings = vision_model->register_module("embeddings", ClipVisionEmbeddings(c, t));
  pre_layrnorm = vision_model->register_module("pre_layrnorm", LayerNorm(c.hidden_size, c.layer_norm_eps, t));
  ClipEncoderOptions encoder_options;
  encoder_options.hidden_size = c.hidden_size;
  encoder_options.intermediate_size = c.intermediate_size;
  encoder_options.num_attention_heads = c.num_attention_heads;
  encoder_options.layer_norm_eps = c.layer_norm_eps;
  encoder_options.activation = c.hidden_act;
  layers = register_clip_encoder(*vision_model, encoder_options, c.num_hidden_layers, t);
  post_layernorm = vision_model->register_module("post_layernorm", LayerNorm(c.hidden_size, c.layer_norm_eps, t));
  visual_projection = register_module("visual_projection", Linear(c.hidden_size, c.projection_dim, false, t));
}

ClipVisionOutput ClipVisionModelWithProjectionImpl::forward(const torch::Tensor& pixel_values, bool output_hidden_states) {
  if (pixel_values.dim() != 4 || pixel_values.size(1) != config.num_channels || pixel_values.size(2) != config.image_size ||
      pixel_values.size(3) != config.image_size)
    throw Error("CLIP vision: pixel_values must be [N, " + std::to_string(config.num_channels) + ", " +
                std::to_string(config.image_size) + ", " + std::to_string(config.image_size) + "], got " +
                c10::str(pixel_values.sizes()));
  // Runs in the dtype of its weights (nn/precision.h); every output is in the dtype of pixel_values.
  const torch::ScalarType out_type = pixel_values.scalar_type();
  ClipVisionOutput out;
  torch::Tensor h = pre_layrnorm->forward(embeddings->forward(pixel_values));
  if (output_hidden_states) out.hidden_states.push_back(h.to(out_type));
  for (auto& layer : layers) {
    h = layer->forward(h);
    if (output_hidden_states) out.hidden_states.push_back(h.to(out_type));
  }
  out.last_hidden_state = h.to(out_type);
  torch::Tensor pooled = post_layernorm->forward(h.select(1, 0));
  out.image_embeds = visual_projection->forward(pooled).to(out_type);
  return out;
}

}  // namespace u3d::nn
