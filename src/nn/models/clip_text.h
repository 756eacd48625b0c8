#pragma once
// transformers CLIPTextModel (SD 1.x's text_encoder): token + position embeddings, the CLIP encoder
// with a causal mask (nn/layers/clip_encoder.h), final LayerNorm, and the pooled output at the end-of-text
// token; built from its config.json with transformers' parameter names (text_model.*). No padding mask:
// Stable Diffusion calls it with the 77 ids only. Load with clip_policy() (older files carry
// text_model.embeddings.position_ids).
#include <nlohmann/json.hpp>
#include <string>
#include <torch/torch.h>
#include <vector>

#include "nn/layers/clip_encoder.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

struct ClipTextConfig {
  int64_t vocab_size = 49408;
  int64_t hidden_size = 512;
  int64_t intermediate_size = 2048;
  int64_t num_hidden_layers = 12;
  int64_t num_attention_heads = 8;
  int64_t max_position_embeddings = 77;
  double layer_norm_eps = 1e-5;
  ClipActivation hidden_act = ClipActivation::kQuickGelu;
  // transformers' pooling rule: with the legacy eos_token_id 2 (SD 1.5's config) the pooled token is the
  // first position of the largest id (the first <|endoftext|>, 49407); otherwise the first eos_token_id.
  int64_t eos_token_id = 2;

  // Accepts a text config or a full CLIPConfig (uses its "text_config").
  static ClipTextConfig from_json(const nlohmann::json& json, const std::string& source);
};

struct ClipTextOutput {
  torch::Tensor last_hidden_state;  // [N, L, hidden] after final_layer_norm: SD's prompt embeddings
  torch::Tensor pooler_output;      // [N, hidden]
  // The embeddings, then each encoder layer's output (before final_layer_norm); filled only when requested.
  std::vector<torch::Tensor> hidden_states;
};

class ClipTextModelImpl : public torch::nn::Module {
 public:
  ClipTextModelImpl(const ClipTextConfig& config, const torch::TensorOptions& options);
  // input_ids int64 [N, L], L <= max_position_embeddings. Outputs in `out_dtype` (the model runs in the
  // dtype of its weights, nn/precision.h).
  ClipTextOutput forward(const torch::Tensor& input_ids, bool output_hidden_states = false,
                         torch::ScalarType out_dtype = torch::kFloat32);

  ClipTextConfig config;
  Embedding token_embedding{nullptr}, position_embedding{nullptr};
  std::vector<ClipEncoderLayer> layers;
  LayerNorm final_layer_norm{nullptr};
};
TORCH_MODULE(ClipTextModel);

}  // namespace u3d::nn
