#pragma once
// IP-Adapter's decoupled cross-attention (diffusers' IPAdapterAttnProcessor) as an attention processor
// for a UNet's attn2 modules. The context the module receives is [text tokens, image tokens]: the last
// `image_tokens` entries are the IP-Adapter's projected image tokens. The queries attend to the text
// tokens through the module's own to_k / to_v and, separately, to the image tokens through the
// processor's to_k_ip / to_v_ip (same heads, same scale); the two results are summed, the image part
// times `scale`, before the module's to_out. Parameters: "to_k_ip.0.weight", "to_v_ip.0.weight"
// (diffusers' names: one entry per adapter, bias-free [inner, cross_attention_dim]).
#include <torch/torch.h>

#include "nn/layers/attention.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

class IpAdapterAttentionProcessor : public AttentionProcessor {
 public:
  // Sized from the attn2 module it goes on (heads, dim_head, cross_attention_dim).
  IpAdapterAttentionProcessor(const AttentionImpl& attention, int64_t image_tokens, double scale,
                              const torch::TensorOptions& options);
  // context [B, L + image_tokens, cross_attention_dim]; a context without room for the image tokens is an Error.
  torch::Tensor process(AttentionImpl& attention, const torch::Tensor& x, const torch::Tensor& context) override;

  int64_t image_tokens;
  double scale;
  Linear to_k_ip{nullptr}, to_v_ip{nullptr};
};

}  // namespace u3d::nn
