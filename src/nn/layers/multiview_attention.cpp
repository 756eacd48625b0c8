#include "nn/layers/multiview_attention.h"

namespace u3d::nn {

MultiViewAttentionProcessor::MultiViewAttentionProcessor(int64_t views_) : views(views_) {
  TORCH_CHECK(views >= 1, "multi-view attention: ", views, " views");
}

torch::Tensor MultiViewAttentionProcessor::process(AttentionImpl& attention, const torch::Tensor& x,
                                                   const torch::Tensor& context) {
  TORCH_CHECK(!context.defined(), "multi-view attention is self-attention: it takes no context");
  const int64_t n = x.size(0), l = x.size(1);
  TORCH_CHECK(n % views == 0, "multi-view attention: batch ", n, " is not a multiple of ", views, " views");
  const torch::Tensor joint = x.reshape({n / views, views * l, x.size(2)});
  const torch::Tensor out = attention.attend(joint, joint);
  return out.reshape({n, l, out.size(2)});
}

}  // namespace u3d::nn
