#include "nn/models/clip_text.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"

namespace u3d::nn {

ClipTextConfig ClipTextConfig::from_json(const nlohmann::json& json, const std::string& source) {
  if (json.is_object() && json.contains("text_config") && json.at("text_config").is_object())
    return from_json(json.at("text_config"), source + " (text_config)");
  ConfigReader r(json, source);
  ClipTextConfig c;
  c.vocab_size = r.get_int("vocab_size", c.vocab_size);
  c.hidden_size = r.get_int("hidden_size", c.hidden_size);
  c.intermediate_size = r.get_int("intermediate_size", c.intermediate_size);
  c.num_hidden_layers = r.get_int("num_hidden_layers", c.num_hidden_layers);
  c.num_attention_heads = r.get_int("num_attention_heads", c.num_attention_heads);
  c.max_position_embeddings = r.get_int("max_position_embeddings", c.max_position_embeddings);
  c.layer_norm_eps = r.get_double("layer_norm_eps", c.layer_norm_eps);
  c.hidden_act = parse_clip_activation(r.get_string("hidden_act", "quick_gelu"), source);
  c.eos_token_id = r.get_int("eos_token_id", c.eos_token_id);
  if (c.hidden_size % c.num_attention_heads != 0)
    throw Error(source + ": hidden_size " + std::to_string(c.hidden_size) + " is not divisible by num_attention_heads " +
                std::to_string(c.num_attention_heads));
  return c;
}

ClipTextModelImpl::ClipTextModelImpl(const ClipTextConfig& c, const torch::TensorOptions& t) : config(c) {
  auto text_model = register_module("text_model", std::make_shared<torch::nn::Module>());
  auto embeddings = text_model->register_module("embeddings", std::make_shared<torch::nn::Module>());
  token_embedding = embeddings->register_module("token_embedding", Embedding(c.vocab_size, c.hidden_size, t));
  position_embedding =
      embeddings->register_module("position_embedding", Embedding(c.max_position_embeddings, c.hidden_size, t));
  ClipEncoderOptions o;
  o.hidden_size = c.hidden_size;
  o.intermediate_size = c.intermediate_size;
  o.num_attention_heads = c.num_attention_heads;
  o.layer_norm_eps = c.layer_norm_eps;
  o.activation = c.hidden_act;
  o.causal = true;
  layers = register_clip_encoder(*text_model, o, c.num_hidden_layers, t);
  final_layer_norm = text_model->register_module("final_layer_norm", LayerNorm(c.hidden_size, c.layer_norm_eps, t));
}

ClipTextOutput ClipTextModelImpl::forward(const torch::Tensor& input_ids, bool output_hidden_states,
                                          torch::ScalarType out_dtype) {
  if (input_ids.dim() != 2 || input_ids.size(1) == 0 || input_ids.size(1) > config.max_position_embeddings ||
      !(input_ids.scalar_type() == torch::kLong || input_ids.scalar_type() == torch::kInt))
    throw Error("CLIP text: input_ids must be integer [N, L] with 1 <= L <= " +
                std::to_string(config.max_position_embeddings) + ", got " + c10::str(input_ids.sizes()));
  const torch::Tensor ids = input_ids.to(torch::kLong);
  if (ids.min().item<int64_t>() < 0 || ids.max().item<int64_t>() >= config.vocab_size)
    throw Error("CLIP text: token ids must be in [0, " + std::to_string(config.vocab_size) + ")");
  const int64_t length = ids.size(1);
  ClipTextOutput out;
  torch::Tensor h = token_embedding->forward(ids) + position_embedding->weight.narrow(0, 0, length).unsqueeze(0);
  if (output_hidden_states) out.hidden_states.push_back(h.to(out_dtype));
  for (auto& layer : layers) {
    h = layer->forward(h);
    if (output_hidden_states) out.hidden_states.push_back(h.to(out_dtype));
  }
  h = final_layer_norm->forward(h);
  out.last_hidden_state = h.to(out_dtype);
  // argmax returns the first maximal position, as torch does.
  const torch::Tensor pooled_at = config.eos_token_id == 2 ? ids.argmax(-1) : (ids == config.eos_token_id).to(torch::kInt).argmax(-1);
  out.pooler_output = h.index({torch::arange(ids.size(0)), pooled_at}).to(out_dtype);
  return out;
}

}  // namespace u3d::nn
