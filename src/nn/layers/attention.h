#pragma once
// Multi-head attention: the shared softmax(q·kᵀ·scale)·v kernel and diffusers' `Attention` module
// (to_q / to_k / to_v / to_out.0, optionally with its own GroupNorm and residual as in the VAE).
#include <torch/torch.h>

#include "nn/layers/layers.h"

namespace u3d::nn {

// q [B, Lq, H*D], k and v [B, Lk, H*D] -> [B, Lq, H*D]. `scale` multiplies q before the product (same
// math as diffusers' alpha on q·kᵀ, and it never uses baddbmm, whose beta=0 path returns NaN on CPU in
// libtorch 1.13). The softmax runs in fp32 for fp16/bf16 inputs (in the input dtype otherwise). Queries are processed in chunks so
// the score matrix of one chunk stays within a fixed budget: 4096-token self-attention never
// materialises B·H·4096·4096 scores at once.
// score_budget: score elements computed per chunk (about 64 MB of fp32 by default).
constexpr int64_t kDefaultAttentionScoreBudget = int64_t{1} << 24;
torch::Tensor multi_head_attention(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v,
                                   int64_t heads, double scale,
                                   int64_t score_budget = kDefaultAttentionScoreBudget);

struct AttentionOptions {
  int64_t query_dim = 0;
  int64_t cross_attention_dim = 0;  // 0: self-attention (keys come from query_dim features)
  int64_t heads = 1;
  int64_t dim_head = 0;
  bool qkv_bias = false;   // UNet: false; VAE mid-block: true
  int64_t norm_groups = 0;  // > 0: GroupNorm on the input (VAE mid-block attention)
  double norm_eps = 1e-6;
  bool residual_connection = false;  // add the input to the output (VAE mid-block attention)
};

class AttentionImpl : public torch::nn::Module {
 public:
  AttentionImpl(const AttentionOptions& options, const torch::TensorOptions& tensor_options);

  // hidden [B, L, C] or [B, C, H, W] (returned in the same layout). context [B, Lk, Ccross] for
  // cross-attention, undefined for self-attention. views > 1 (self-attention only): the tokens of each
  // group of `views` consecutive batch entries attend jointly (Unique3D's multi-view attention).
  torch::Tensor forward(const torch::Tensor& hidden, const torch::Tensor& context = {}, int64_t views = 1);

  AttentionOptions options;
  GroupNorm group_norm{nullptr};
  Linear to_q{nullptr}, to_k{nullptr}, to_v{nullptr};
  torch::nn::ModuleList to_out;  // [0]: output Linear (index 1 is dropout in Python: no parameters)
  Linear out_proj{nullptr};
};
TORCH_MODULE(Attention);

}  // namespace u3d::nn
