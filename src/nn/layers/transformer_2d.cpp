#include "nn/layers/transformer_2d.h"

#include "nn/layers/geglu_kernel.h"

#include <algorithm>

namespace u3d::nn {

namespace {

// The feed-forward works on each token alone, so a long input goes through in blocks of rows (batch x
// tokens) whose GEGLU hidden layer, 8 x dim values a row, holds at most this many values (32 MiB in
// fp32). Whole, it is 2 x 4,096 x 5,120 values (168 MB) at the second level of a 1024 px image at
// batch 2, and the largest tensor of a refinement step.
constexpr int64_t kFeedForwardHiddenValues = int64_t{1} << 23;

}  // namespace

GEGLUImpl::GEGLUImpl(int64_t dim_in, int64_t dim_out, const torch::TensorOptions& t) {
  proj = register_module("proj", Linear(dim_in, 2 * dim_out, true, t));
  proj->split_output_halves();
}

torch::Tensor GEGLUImpl::forward(const torch::Tensor& x) {
  if (proj->gated_forward_applies(x)) return proj->gated_forward(x);
  const torch::Tensor projected = proj->forward(x);
  if (geglu_applies(projected)) return geglu(projected);
  auto halves = projected.chunk(2, -1);
  return halves[0] * torch::gelu(halves[1]);
}

FeedForwardImpl::FeedForwardImpl(int64_t dim, const torch::TensorOptions& t) {
  geglu = GEGLU(dim, 4 * dim, t);
  proj_out = Linear(4 * dim, dim, true, t);
  // Index 1 is Python's Dropout: kept as an Identity so the output Linear is net.2 as in the checkpoints.
  net = register_module("net", torch::nn::ModuleList(geglu, torch::nn::Identity(), proj_out));
}

torch::Tensor FeedForwardImpl::forward(const torch::Tensor& x) {
  const int64_t block = std::max<int64_t>(kFeedForwardHiddenValues / geglu->proj->weight.size(0), 1);
  const torch::Tensor rows = x.reshape({-1, x.size(-1)});
  if (rows.size(0) <= block) return proj_out->forward(geglu->forward(x));
  torch::Tensor out = torch::empty({rows.size(0), proj_out->weight.size(0)}, x.options());
  for (int64_t start = 0; start < rows.size(0); start += block) {
    const int64_t n = std::min(block, rows.size(0) - start);
    out.narrow(0, start, n).copy_(proj_out->forward(geglu->forward(rows.narrow(0, start, n))));
  }
  std::vector<int64_t> sizes = x.sizes().vec();
  sizes.back() = out.size(1);
  return out.reshape(sizes);
}

BasicTransformerBlockImpl::BasicTransformerBlockImpl(int64_t dim, int64_t heads, int64_t dim_head,
                                                     int64_t cross_attention_dim, const torch::TensorOptions& t) {
  AttentionOptions self_attn;
  self_attn.query_dim = dim;
  self_attn.heads = heads;
  self_attn.dim_head = dim_head;
  AttentionOptions cross_attn = self_attn;
  cross_attn.cross_attention_dim = cross_attention_dim;
  norm1 = register_module("norm1", LayerNorm(dim, 1e-5, t));
  attn1 = register_module("attn1", Attention(self_attn, t));
  norm2 = register_module("norm2", LayerNorm(dim, 1e-5, t));
  attn2 = register_module("attn2", Attention(cross_attn, t));
  norm3 = register_module("norm3", LayerNorm(dim, 1e-5, t));
  ff = register_module("ff", FeedForward(dim, t));
}

torch::Tensor BasicTransformerBlockImpl::forward(const torch::Tensor& x, const torch::Tensor& encoder_hidden_states) {
  // The residuals are added into the fresh outputs in place (the same sums), so no third map of the
  // block's size is allocated for them.
  torch::Tensor h = attn1->forward(norm1->forward(x)).add_(x);
  h.add_(attn2->forward(norm2->forward(h), encoder_hidden_states));
  return h.add_(ff->forward(norm3->forward(h)));
}

Transformer2DModelImpl::Transformer2DModelImpl(int64_t heads, int64_t dim_head, int64_t in_channels, int64_t layers,
                                               int64_t norm_groups, int64_t cross_attention_dim,
                                               const torch::TensorOptions& t) {
  const int64_t inner = heads * dim_head;
  norm = register_module("norm", GroupNorm(norm_groups, in_channels, 1e-6, t));
  proj_in = register_module("proj_in", Conv2d(in_channels, inner, 1, 1, 0, true, t));
  transformer_blocks = register_module("transformer_blocks", torch::nn::ModuleList());
  for (int64_t i = 0; i < layers; ++i) {
    blocks.push_back(BasicTransformerBlock(inner, heads, dim_head, cross_attention_dim, t));
    transformer_blocks->push_back(blocks.back());
  }
  proj_out = register_module("proj_out", Conv2d(inner, in_channels, 1, 1, 0, true, t));
}

torch::Tensor Transformer2DModelImpl::forward(const torch::Tensor& x, const torch::Tensor& encoder_hidden_states) {
  const int64_t b = x.size(0), h = x.size(2), w = x.size(3);
  torch::Tensor tokens = proj_in->forward(norm->forward(x));
  const int64_t inner = tokens.size(1);
  tokens = tokens.permute({0, 2, 3, 1}).reshape({b, h * w, inner});
  for (auto& block : blocks) tokens = block->forward(tokens, encoder_hidden_states);
  // The tokens are the output map in channels-last order: the convolution reads them where they are
  // (nn/layers/onednn_conv.h), with no copy into NCHW and back.
  const torch::Tensor out = tokens.reshape({b, h, w, inner}).permute({0, 3, 1, 2});
  return proj_out->forward(out).add_(x);
}

}  // namespace u3d::nn
