#pragma once
// diffusers Transformer2DModel as the SD 1.x UNet uses it (continuous input, 1x1-conv projections) with
// its BasicTransformerBlocks (self-attention, cross-attention, GEGLU feed-forward), named as in diffusers.
#include <torch/torch.h>

#include "nn/layers/attention.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

// GEGLU: proj -> split in halves (hidden, gate) -> hidden * gelu(gate), the gate being the SECOND half,
// with the exact erf GELU. Where oneDNN's path applies, the two halves are two products with the gating
// applied as they are written (LinearImpl::gated_forward); elsewhere the projection is gated after it.
class GEGLUImpl : public torch::nn::Module {
 public:
  GEGLUImpl(int64_t dim_in, int64_t dim_out, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  Linear proj{nullptr};
};
TORCH_MODULE(GEGLU);

// FeedForward: net.0 = GEGLU(dim, 4·dim), net.1 = dropout (identity), net.2 = Linear(4·dim, dim).
class FeedForwardImpl : public torch::nn::Module {
 public:
  FeedForwardImpl(int64_t dim, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::ModuleList net;
  GEGLU geglu{nullptr};
  Linear proj_out{nullptr};
};
TORCH_MODULE(FeedForward);

// BasicTransformerBlock (layer_norm variant): x += attn1(norm1 x); x += attn2(norm2 x, context);
// x += ff(norm3 x). LayerNorm eps 1e-5. encoder_hidden_states: the context, [B, Lk, cross_attention_dim].
class BasicTransformerBlockImpl : public torch::nn::Module {
 public:
  BasicTransformerBlockImpl(int64_t dim, int64_t heads, int64_t dim_head, int64_t cross_attention_dim,
                            const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& encoder_hidden_states);
  LayerNorm norm1{nullptr}, norm2{nullptr}, norm3{nullptr};
  Attention attn1{nullptr}, attn2{nullptr};
  FeedForward ff{nullptr};
};
TORCH_MODULE(BasicTransformerBlock);

// Transformer2DModel: GroupNorm (eps 1e-6) -> proj_in (1x1 conv) -> tokens -> blocks -> proj_out (1x1
// conv) -> + input.
class Transformer2DModelImpl : public torch::nn::Module {
 public:
  Transformer2DModelImpl(int64_t heads, int64_t dim_head, int64_t in_channels, int64_t layers, int64_t norm_groups,
                         int64_t cross_attention_dim, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& encoder_hidden_states);
  GroupNorm norm{nullptr};
  Conv2d proj_in{nullptr}, proj_out{nullptr};
  torch::nn::ModuleList transformer_blocks;
  std::vector<BasicTransformerBlock> blocks;
};
TORCH_MODULE(Transformer2DModel);

}  // namespace u3d::nn
