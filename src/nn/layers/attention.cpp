#include "nn/layers/attention.h"

#include "nn/layers/attention_kernel.h"
#include "nn/layers/softmax_kernel.h"

#include <ATen/Parallel.h>
#include <ATen/ThreadLocalState.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace u3d::nn {

namespace {

// [B, L, H*D] -> [B*H, L, D], contiguous.
torch::Tensor split_heads(const torch::Tensor& x, int64_t heads) {
  const int64_t b = x.size(0), l = x.size(1), d = x.size(2) / heads;
  return x.reshape({b, l, heads, d}).permute({0, 2, 1, 3}).reshape({b * heads, l, d});
}

// [B*H, L, D] -> [B, L, H*D].
torch::Tensor merge_heads(const torch::Tensor& x, int64_t heads) {
  const int64_t bh = x.size(0), l = x.size(1), d = x.size(2);
  return x.reshape({bh / heads, heads, l, d}).permute({0, 2, 1, 3}).reshape({bh / heads, l, heads * d});
}

// Softmax computed in at least fp32, returned in the scores' dtype. ATen's bf16 softmax already
// computes in fp32 and rounds once (equal to the fp32 softmax rounded to bf16; test_precision checks
// it) and is about 20x faster on the CPU than softmax(dtype=float) followed by a cast; fp16 is upcast.
torch::Tensor softmax_fp32(const torch::Tensor& scores) {
  if (scores.scalar_type() != torch::kHalf) return scores.softmax(-1);
  return scores.softmax(-1, torch::kFloat).to(scores.scalar_type());
}

// softmax(q·kᵀ·scale) for q [.., Lq, D] and keys_t = kᵀ [.., D, Lk], in q's dtype. bf16 on the CPU goes
// through scaled_softmax_ (the product unscaled, the scale applied in fp32); other dtypes scale q before
// the product and use softmax_fp32.
torch::Tensor attention_probabilities(const torch::Tensor& q, const torch::Tensor& keys_t, double scale) {
  if (q.device().is_cpu() && q.scalar_type() == torch::kBFloat16) {
    torch::Tensor scores = torch::matmul(q, keys_t).contiguous();
    scaled_softmax_(scores, scale);
    return scores;
  }
  return softmax_fp32(torch::matmul(q * scale, keys_t));
}

}  // namespace

torch::Tensor multi_head_attention(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v,
                                   int64_t heads, double scale, int64_t score_budget) {
  TORCH_CHECK(q.dim() == 3 && k.dim() == 3 && v.dim() == 3, "attention expects [B, L, C] inputs");
  TORCH_CHECK(q.size(2) % heads == 0, "attention: ", q.size(2), " channels do not split into ", heads, " heads");
  if (fused_attention_applies(q, k, v, heads)) return fused_attention(q, k, v, heads, scale);
  const int64_t batch = q.size(0), lq = q.size(1), lk = k.size(1), dim = q.size(2) / heads;
  if (batch * heads * lq * lk <= score_budget) {
    const torch::Tensor p =
        attention_probabilities(split_heads(q, heads), split_heads(k, heads).transpose(1, 2), scale);
    return merge_heads(torch::bmm(p, split_heads(v, heads)), heads);
  }

  // Each task takes one sample's head (or a range of its queries, where there are fewer heads than
  // threads to keep busy), copies that head's keys and values into two small contiguous matrices, and
  // goes through its queries in blocks of at most `score_budget` scores, single-threaded inside. A
  // block's queries are read from q and its output rows written into the result in place: no
  // head-split copy of q, k, v or the output is made.
  const torch::Tensor q4 = q.reshape({batch, lq, heads, dim});
  const torch::Tensor k4 = k.reshape({batch, lk, heads, dim});
  const torch::Tensor v4 = v.reshape({batch, lk, heads, dim});
  torch::Tensor out = torch::empty({batch, lq, heads * dim}, v.options());
  const torch::Tensor out4 = out.view({batch, lq, heads, dim});
  const int64_t chunk = std::clamp<int64_t>(score_budget / std::max<int64_t>(lk, 1), 1, std::max<int64_t>(lq, 1));
  const int64_t blocks_per_head = (lq + chunk - 1) / chunk;
  const int64_t wanted_tasks = 4 * static_cast<int64_t>(at::get_num_threads());
  const int64_t parts = std::clamp<int64_t>((wanted_tasks + batch * heads - 1) / (batch * heads), 1, blocks_per_head);
  const int64_t blocks_per_part = (blocks_per_head + parts - 1) / parts;
  // With many keys, oneDNN's bf16 product of the probabilities [n, Lk] and values [Lk, D] is slow for
  // D = 40 output columns (one 256-query block at 4,096 keys: 0.49 ms); computed as valuesᵀ·pᵀ, with
  // n columns, it took 0.31 ms.
  const bool transposed_product = q.scalar_type() == torch::kBFloat16 && q.device().is_cpu() && lk >= 2048;
  const at::ThreadLocalState caller_state;  // inference mode and grad mode for the worker threads
  at::parallel_for(0, batch * heads * parts, 1, [&](int64_t begin, int64_t end) {
    at::ThreadLocalStateGuard state_guard(caller_state);
    for (int64_t task = begin; task < end; ++task) {
      const int64_t sample = task / (heads * parts), head = task / parts % heads, part = task % parts;
      const torch::Tensor keys_t = k4.select(0, sample).select(1, head).contiguous().t();
      const torch::Tensor head_values = v4.select(0, sample).select(1, head);
      const torch::Tensor values = transposed_product ? head_values.t().contiguous() : head_values.contiguous();
      const torch::Tensor queries = q4.select(0, sample).select(1, head);
      const torch::Tensor target = out4.select(0, sample).select(1, head);
      for (int64_t block = part * blocks_per_part; block < std::min((part + 1) * blocks_per_part, blocks_per_head);
           ++block) {
        const int64_t start = block * chunk, n = std::min(chunk, lq - start);
        const torch::Tensor p = attention_probabilities(queries.narrow(0, start, n), keys_t, scale);
        target.narrow(0, start, n).copy_(transposed_product ? torch::mm(values, p.t()).t() : torch::mm(p, values));
      }
    }
  });
  return out;
}

torch::Tensor causal_multi_head_attention(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v,
                                          int64_t heads, double scale) {
  TORCH_CHECK(q.dim() == 3 && q.sizes() == k.sizes() && k.sizes() == v.sizes(),
              "causal attention expects equal [B, L, C] inputs");
  TORCH_CHECK(q.size(2) % heads == 0, "attention: ", q.size(2), " channels do not split into ", heads, " heads");
  torch::Tensor scores = torch::bmm(split_heads(q * scale, heads), split_heads(k, heads).transpose(1, 2));
  const int64_t l = q.size(1);
  const torch::Tensor future =
      torch::ones({l, l}, torch::TensorOptions().dtype(torch::kBool).device(q.device())).triu(1);
  scores = scores.masked_fill(future, -std::numeric_limits<double>::infinity());
  return merge_heads(torch::bmm(softmax_fp32(scores), split_heads(v, heads)), heads);
}

torch::Tensor PlainAttentionProcessor::process(AttentionImpl& attention, const torch::Tensor& x,
                                               const torch::Tensor& context) {
  return attention.attend(x, context.defined() ? context : x);
}

AttentionImpl::AttentionImpl(const AttentionOptions& o, const torch::TensorOptions& t) : options(o) {
  const int64_t inner = o.heads * o.dim_head;
  const int64_t kv_dim = o.cross_attention_dim > 0 ? o.cross_attention_dim : o.query_dim;
  // Registration order follows diffusers so named_parameters() lists keys the same way.
  if (o.norm_groups > 0)
    group_norm = register_module("group_norm", GroupNorm(o.norm_groups, o.query_dim, o.norm_eps, t));
  to_q = register_module("to_q", Linear(o.query_dim, inner, o.qkv_bias, t));
  to_k = register_module("to_k", Linear(kv_dim, inner, o.qkv_bias, t));
  to_v = register_module("to_v", Linear(kv_dim, inner, o.qkv_bias, t));
  out_proj = Linear(inner, o.query_dim, true, t);
  to_out = register_module("to_out", torch::nn::ModuleList(out_proj));
  processor = register_module("processor", std::make_shared<PlainAttentionProcessor>());
}

torch::Tensor AttentionImpl::forward(const torch::Tensor& hidden, const torch::Tensor& context) {
  torch::Tensor x = hidden;
  const bool spatial = x.dim() == 4;
  int64_t b = 0, c = 0, h = 0, w = 0;
  if (spatial) {
    b = x.size(0), c = x.size(1), h = x.size(2), w = x.size(3);
    x = x.reshape({b, c, h * w}).transpose(1, 2);
  }
  const torch::Tensor residual = x;
  if (group_norm) x = group_norm->forward(x.transpose(1, 2)).transpose(1, 2);

  torch::Tensor out = processor->process(*this, x, context);

  if (options.residual_connection) out = out + residual;
  if (spatial) out = out.transpose(1, 2).reshape({b, c, h, w});
  return out;
}

torch::Tensor AttentionImpl::attend(const torch::Tensor& x, const torch::Tensor& kv) {
  const double scale = 1.0 / std::sqrt(static_cast<double>(options.dim_head));
  return out_proj->forward(
      multi_head_attention(to_q->forward(x), to_k->forward(kv), to_v->forward(kv), options.heads, scale));
}

void AttentionImpl::set_processor(std::shared_ptr<AttentionProcessor> p) {
  TORCH_CHECK(p, "Attention: the processor must not be null");
  processor = replace_module("processor", std::move(p));
}

size_t set_attention_processors(torch::nn::Module& model, const AttentionProcessorChooser& choose) {
  size_t changed = 0;
  for (const auto& item : model.named_modules("", /*include_self=*/false)) {
    auto* attention = dynamic_cast<AttentionImpl*>(item.value().get());
    if (!attention) continue;
    if (auto p = choose(item.key(), *attention)) {
      attention->set_processor(std::move(p));
      ++changed;
    }
  }
  return changed;
}

AttentionProcessorChooser self_attention_only(std::shared_ptr<AttentionProcessor> processor) {
  return [processor = std::move(processor)](const std::string& name, const AttentionImpl&) {
    return name == "attn1" || name.ends_with(".attn1") ? processor : nullptr;
  };
}

}  // namespace u3d::nn
