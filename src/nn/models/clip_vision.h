#pragma once
// transformers CLIPVisionModelWithProjection (ViT: patch + class embeddings, pre-LayerNorm encoder with
// quick_gelu or GELU MLPs (nn/layers/clip_encoder.h), post-LayerNorm on the class token, bias-free visual projection), built from its
// config.json with transformers' parameter names (vision_model.*, visual_projection.weight).
#include <nlohmann/json.hpp>
#include <string>
#include <torch/torch.h>
#include <vector>

#include "nn/checkpoint/tensor_map.h"
#include "nn/layers/clip_encoder.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

struct ClipVisionConfig {
  int64_t hidden_size = 768;
  int64_t intermediate_size = 3072;
  int64_t num_hidden_layers = 12;
  int64_t num_attention_heads = 12;
  int64_t num_channels = 3;
  int64_t image_size = 224;
  int64_t patch_size = 32;
  int64_t projection_dim = 512;
  double layer_norm_eps = 1e-5;
  ClipActivation hidden_act = ClipActivation::kQuickGelu;

  // Accepts a vision config or a full CLIPConfig (uses its "vision_config").
  static ClipVisionConfig from_json(const nlohmann::json& json, const std::string& source);
};

// Older checkpoints carry the buffer vision_model.embeddings.position_ids (always arange); current
// transformers ignores it. Removes it so a strict load sees only parameters.
void drop_clip_vision_position_ids(TensorMap& state_dict);

class ClipVisionEmbeddingsImpl : public torch::nn::Module {
 public:
  ClipVisionEmbeddingsImpl(const ClipVisionConfig& config, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& pixel_values);
  torch::Tensor class_embedding;
  Conv2d patch_embedding{nullptr};
  Embedding position_embedding{nullptr};
};
TORCH_MODULE(ClipVisionEmbeddings);

struct ClipVisionOutput {
  torch::Tensor image_embeds;       // [N, projection_dim]
  torch::Tensor last_hidden_state;  // [N, 1 + patches, hidden] (no post-LayerNorm)
  // The encoder input (embeddings after pre_layrnorm, as transformers records it), then each encoder
  // layer's output; filled only when requested.
  std::vector<torch::Tensor> hidden_states;
};

class ClipVisionModelWithProjectionImpl : public torch::nn::Module {
 public:
  ClipVisionModelWithProjectionImpl(const ClipVisionConfig& config, const torch::TensorOptions& options);
  // pixel_values [N, 3, image_size, image_size] as produced by ClipImageProcessor.
  ClipVisionOutput forward(const torch::Tensor& pixel_values, bool output_hidden_states = false);

  ClipVisionConfig config;
  ClipVisionEmbeddings embeddings{nullptr};
  LayerNorm pre_layrnorm{nullptr}, post_layernorm{nullptr};  // "layrnorm": transformers' key spelling
  std::vector<ClipEncoderLayer> layers;
  Linear visual_projection{nullptr};
};
TORCH_MODULE(ClipVisionModelWithProjection);

}  // namespace u3d::nn
