#pragma once
// Unique3D's multi-view self-attention as an attention processor: the tokens of each group of `views`
// consecutive batch entries (the views of one object) attend jointly, as the tokens of one image would.
// Set it on a UNet's attn1 modules: set_attention_processors(*unet, self_attention_only(processor)).
#include <torch/torch.h>

#include "nn/layers/attention.h"

namespace u3d::nn {

class MultiViewAttentionProcessor : public AttentionProcessor {
 public:
  explicit MultiViewAttentionProcessor(int64_t views);
  // Self-attention only (an undefined context); the batch must be a multiple of `views`.
  torch::Tensor process(AttentionImpl& attention, const torch::Tensor& x, const torch::Tensor& context) override;

  int64_t views;
};

}  // namespace u3d::nn
