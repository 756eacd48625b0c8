#include "nn/layers/ip_adapter_attention.h"

#include <cmath>

#include "core/error.h"

namespace u3d::nn {

IpAdapterAttentionProcessor::IpAdapterAttentionProcessor(const AttentionImpl& attention, int64_t image_tokens_,
                                                         double scale_, const torch::TensorOptions& t)
    : image_tokens(image_tokens_), scale(scale_) {
  const AttentionOptions& o = attention.options;
  TORCH_CHECK(o.cross_attention_dim > 0, "IP-Adapter: the processor belongs on a cross-attention module");
  const int64_t inner = o.heads * o.dim_head;
  to_k_ip = Linear(o.cross_attention_dim, inner, false, t);
  to_v_ip = Linear(o.cross_attention_dim, inner, false, t);
  register_module("to_k_ip", torch::nn::ModuleList(to_k_ip));
  register_module("to_v_ip", torch::nn::ModuleList(to_v_ip));
}

torch::Tensor IpAdapterAttentionProcessor::process(AttentionImpl& attention, const torch::Tensor& x,
                                                   const torch::Tensor& context) {
  if (!context.defined() || context.dim() != 3 || context.size(1) <= image_tokens)
    throw Error("IP-Adapter attention: the context must hold text tokens followed by " + std::to_string(image_tokens) +
                " image tokens, got " + (context.defined() ? c10::str(context.sizes()) : std::string("none")));
  const AttentionOptions& o = attention.options;
  const double s = 1.0 / std::sqrt(static_cast<double>(o.dim_head));
  const int64_t text_tokens = context.size(1) - image_tokens;
  const torch::Tensor text = context.narrow(1, 0, text_tokens);
  const torch::Tensor image = context.narrow(1, text_tokens, image_tokens);
  const torch::Tensor q = attention.to_q->forward(x);
  torch::Tensor h = multi_head_attention(q, attention.to_k->forward(text), attention.to_v->forward(text), o.heads, s);
  h = h + scale * multi_head_attention(q, to_k_ip->forward(image), to_v_ip->forward(image), o.heads, s);
  return attention.out_proj->forward(h);
}

}  // namespace u3d::nn
