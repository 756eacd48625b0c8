#include "nn/layers/clip_encoder.h"

#include <cmath>

#include "core/error.h"
#include "nn/layers/attention.h"

namespace u3d::nn {

ClipAttentionImpl::ClipAttentionImpl(int64_t dim, int64_t heads_, bool causal_, const torch::TensorOptions& t)
    : heads(heads_), causal(causal_) {
  k_proj = register_module("k_proj", Linear(dim, dim, true, t));
  v_proj = register_module("v_proj", Linear(dim, dim, true, t));
  q_proj = register_module("q_proj", Linear(dim, dim, true, t));
  out_proj = register_module("out_proj", Linear(dim, dim, true, t));
}

torch::Tensor ClipAttentionImpl::forward(const torch::Tensor& x) {
  const double scale = 1.0 / std::sqrt(static_cast<double>(x.size(2) / heads));
  const torch::Tensor q = q_proj->forward(x), k = k_proj->forward(x), v = v_proj->forward(x);
  return out_proj->forward(causal ? causal_multi_head_attention(q, k, v, heads, scale)
                                  : multi_head_attention(q, k, v, heads, scale));
}

ClipActivation parse_clip_activation(const std::string& hidden_act, const std::string& source) {
  if (hidden_act == "quick_gelu") return ClipActivation::kQuickGelu;
  if (hidden_act == "gelu") return ClipActivation::kGelu;
  throw Error(source + ": hidden_act = \"" + hidden_act + "\" is not supported (quick_gelu or gelu)");
}

ClipMlpImpl::ClipMlpImpl(int64_t dim, int64_t hidden, ClipActivation activation_, const torch::TensorOptions& t)
    : activation(activation_) {
  fc1 = register_module("fc1", Linear(dim, hidden, true, t));
  fc2 = register_module("fc2", Linear(hidden, dim, true, t));
}

torch::Tensor ClipMlpImpl::forward(const torch::Tensor& x) {
  torch::Tensor h = fc1->forward(x);
  h = activation == ClipActivation::kGelu ? torch::gelu(h) : h * torch::sigmoid(1.702 * h);
  return fc2->forward(h);
}

ClipEncoderLayerImpl::ClipEncoderLayerImpl(const ClipEncoderOptions& o, const torch::TensorOptions& t) {
  self_attn = register_module("self_attn", ClipAttention(o.hidden_size, o.num_attention_heads, o.causal, t));
  layer_norm1 = register_module("layer_norm1", LayerNorm(o.hidden_size, o.layer_norm_eps, t));
  mlp = register_module("mlp", ClipMlp(o.hidden_size, o.intermediate_size, o.activation, t));
  layer_norm2 = register_module("layer_norm2", LayerNorm(o.hidden_size, o.layer_norm_eps, t));
}

torch::Tensor ClipEncoderLayerImpl::forward(const torch::Tensor& x) {
  torch::Tensor h = x + self_attn->forward(layer_norm1->forward(x));
  return h + mlp->forward(layer_norm2->forward(h));
}

std::vector<ClipEncoderLayer> register_clip_encoder(torch::nn::Module& parent, const ClipEncoderOptions& options,
                                                    int64_t num_layers, const torch::TensorOptions& t) {
  auto encoder = parent.register_module("encoder", std::make_shared<torch::nn::Module>());
  auto list = encoder->register_module("layers", torch::nn::ModuleList());
  std::vector<ClipEncoderLayer> layers;
  for (int64_t i = 0; i < num_layers; ++i) {
    layers.push_back(ClipEncoderLayer(options, t));
    list->push_back(layers.back());
  }
  return layers;
}

}  // namespace u3d::nn
