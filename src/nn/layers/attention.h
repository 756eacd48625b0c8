#pragma once
// Multi-head attention: the shared softmax(q·kᵀ·scale)·v kernel, diffusers' `Attention` module
// (to_q / to_k / to_v / to_out.0, optionally with its own GroupNorm and residual as in the VAE) and
// the processor hook through which a model variant changes what one Attention module attends over.
//
// Attention::forward does the layout work (spatial <-> tokens, GroupNorm, residual) and hands the
// tokens to its processor, which returns the projected attention output. The default,
// PlainAttentionProcessor, attends over the context (the input itself for self-attention). A variant
// is an AttentionProcessor subclass that set_attention_processors() puts on the modules a chooser
// picks by their dotted names in the model, as diffusers' set_attn_processor does with its dict:
//  - Unique3D's multi-view self-attention (nn/layers/multiview_attention.h) on every attn1;
//  - reference attention (nn/layers/reference_attention.h): a "write" processor on the reference UNet's
//    attn1 modules records its input tokens in a store under the module's name, and a "read" processor
//    on the main UNet's attn1 modules, sharing that store, adds an attention over the recorded tokens;
//  - IP-Adapter: a processor on attn2 that owns to_k_ip / to_v_ip (sized from the module the chooser
//    is given), splits the trailing image tokens off the context and adds their attention to the
//    text attention.
// The processor is the module's registered submodule "processor", so a processor's own parameters load
// by name like any other: diffusers' "<attn2>.processor.to_k_ip.0.weight", Unique3D's
// "<attn1>.processor.crosspond_attention.to_q.weight".
#include <torch/torch.h>

#include <functional>
#include <memory>
#include <string>

#include "nn/layers/layers.h"

namespace u3d::nn {

// q [B, Lq, H*D], k and v [B, Lk, H*D] -> [B, Lq, H*D]. fp32 and bf16 on the CPU (with avx512_bf16 for
// bf16), at head sizes that are multiples of 8, go to the fused kernel (nn/layers/attention_kernel.h:
// online softmax over blocks of keys, no score matrix; `score_budget` plays no part there). Otherwise
// `scale` multiplies q before the product (same math as diffusers' alpha on q·kᵀ, and it never uses
// baddbmm, whose beta=0 path returns NaN on CPU in libtorch 1.13); in bf16 on the CPU it multiplies the
// scores in fp32 inside the softmax kernel (nn/layers/softmax_kernel.h). The softmax computes in fp32
// for fp16/bf16 inputs and returns their dtype. When all B·H·Lq·Lk scores exceed `score_budget`
// elements, each head's queries go in blocks of at most that many scores, one block per thread at a
// time, reading q, k, v and writing the output in place. The default, 4 MiB of fp32 scores a thread,
// is 64 queries a block at 16,384 keys (docs/networks.md).
constexpr int64_t kDefaultAttentionScoreBudget = int64_t{1} << 20;
torch::Tensor multi_head_attention(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v,
                                   int64_t heads, double scale,
                                   int64_t score_budget = kDefaultAttentionScoreBudget);

// multi_head_attention with a causal mask (query i sees keys 0..i), as CLIP's text encoder; q, k and v
// have the same length. Computed in one block: meant for short sequences (77 tokens).
torch::Tensor causal_multi_head_attention(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v,
                                          int64_t heads, double scale);

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

class AttentionImpl;

// Computes an Attention module's output from its input tokens.
class AttentionProcessor : public torch::nn::Module {
 public:
  // x [B, L, query_dim]: the module's input in token layout, after its GroupNorm; context as given to
  // Attention::forward. Returns [B, L, query_dim] after to_out, before any residual.
  virtual torch::Tensor process(AttentionImpl& attention, const torch::Tensor& x, const torch::Tensor& context) = 0;
};

// Queries from x; keys and values from the context, or from x itself when the context is undefined.
class PlainAttentionProcessor : public AttentionProcessor {
 public:
  torch::Tensor process(AttentionImpl& attention, const torch::Tensor& x, const torch::Tensor& context) override;
};

class AttentionImpl : public torch::nn::Module {
 public:
  AttentionImpl(const AttentionOptions& options, const torch::TensorOptions& tensor_options);

  // hidden [B, L, C] or [B, C, H, W] (returned in the same layout). context [B, Lk, Ccross] for
  // cross-attention, undefined for self-attention.
  torch::Tensor forward(const torch::Tensor& hidden, const torch::Tensor& context = {});

  // The projections and the kernel, for processors: to_out(softmax(to_q(x)·to_k(kv)ᵀ/√dim_head)·to_v(kv)),
  // x [B, L, query_dim], kv [B, Lk, C] -> [B, L, query_dim].
  torch::Tensor attend(const torch::Tensor& x, const torch::Tensor& kv);

  // Replaces the processor (the registered submodule "processor").
  void set_processor(std::shared_ptr<AttentionProcessor> processor);

  AttentionOptions options;
  GroupNorm group_norm{nullptr};
  Linear to_q{nullptr}, to_k{nullptr}, to_v{nullptr};
  torch::nn::ModuleList to_out;  // [0]: output Linear (index 1 is dropout in Python: no parameters)
  Linear out_proj{nullptr};
  std::shared_ptr<AttentionProcessor> processor;  // a PlainAttentionProcessor unless set otherwise
};
TORCH_MODULE(Attention);

// Picks the processor for one Attention module of a model, given its dotted name there (e.g.
// "down_blocks.1.attentions.0.transformer_blocks.0.attn1") and the module; nullptr leaves the module's
// processor as it is.
using AttentionProcessorChooser =
    std::function<std::shared_ptr<AttentionProcessor>(const std::string& name, const AttentionImpl& attention)>;

// Offers every Attention module inside `model` to `choose`; returns how many got a new processor.
size_t set_attention_processors(torch::nn::Module& model, const AttentionProcessorChooser& choose);

// A chooser that gives `processor` to the transformer blocks' self-attention (modules named attn1) only.
AttentionProcessorChooser self_attention_only(std::shared_ptr<AttentionProcessor> processor);

}  // namespace u3d::nn
