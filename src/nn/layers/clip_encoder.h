#pragma once
// The transformer layers both CLIP towers share (transformers' CLIPAttention, CLIPMLP,
// CLIPEncoderLayer): pre-LayerNorm residual blocks of multi-head attention with biased q/k/v/out
// projections and an MLP with quick_gelu (OpenAI's CLIP) or the exact GELU (OpenCLIP's ViT-H/14, the
// IP-Adapter image encoder). The text tower attends causally, the vision tower over all tokens.
#include <torch/torch.h>

#include <string>

#include "nn/layers/layers.h"

namespace u3d::nn {

enum class ClipActivation { kQuickGelu, kGelu };

// transformers' "hidden_act": "quick_gelu" or "gelu"; anything else is an Error naming `source`.
ClipActivation parse_clip_activation(const std::string& hidden_act, const std::string& source);

struct ClipEncoderOptions {
  int64_t hidden_size = 768;
  int64_t intermediate_size = 3072;
  int64_t num_attention_heads = 12;
  double layer_norm_eps = 1e-5;
  ClipActivation activation = ClipActivation::kQuickGelu;
  bool causal = false;  // each token attends to itself and the tokens before it (text encoder)
};

class ClipAttentionImpl : public torch::nn::Module {
 public:
  ClipAttentionImpl(int64_t dim, int64_t heads, bool causal, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  Linear k_proj{nullptr}, v_proj{nullptr}, q_proj{nullptr}, out_proj{nullptr};
  int64_t heads;
  bool causal;
};
TORCH_MODULE(ClipAttention);

class ClipMlpImpl : public torch::nn::Module {
 public:
  ClipMlpImpl(int64_t dim, int64_t hidden, ClipActivation activation, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);  // fc2(activation(fc1(x)))
  Linear fc1{nullptr}, fc2{nullptr};
  ClipActivation activation;
};
TORCH_MODULE(ClipMlp);

// x + attn(ln1 x), then + mlp(ln2 ·).
class ClipEncoderLayerImpl : public torch::nn::Module {
 public:
  ClipEncoderLayerImpl(const ClipEncoderOptions& options, const torch::TensorOptions& tensor_options);
  torch::Tensor forward(const torch::Tensor& x);
  ClipAttention self_attn{nullptr};
  LayerNorm layer_norm1{nullptr}, layer_norm2{nullptr};
  ClipMlp mlp{nullptr};
};
TORCH_MODULE(ClipEncoderLayer);

// transformers' CLIPEncoder: "encoder.layers.<i>" under `parent`. Returns the layers in order.
std::vector<ClipEncoderLayer> register_clip_encoder(torch::nn::Module& parent, const ClipEncoderOptions& options,
                                                    int64_t num_layers, const torch::TensorOptions& tensor_options);

}  // namespace u3d::nn
