#include "nn/pipelines/guidance.h"

#include "core/error.h"

namespace u3d::nn {

GuidedPrediction guided_prediction(double scale, const std::function<torch::Tensor(GuidanceHalf)>& predict,
                                   bool keep_raw) {
  const torch::Tensor uncond = predict(GuidanceHalf::kUnconditional);
  torch::Tensor cond = predict(GuidanceHalf::kConditional);
  if (uncond.sizes() != cond.sizes())
    throw Error("guidance: the two halves' predictions differ in shape, " + c10::str(uncond.sizes()) + " and " +
                c10::str(cond.sizes()));
  GuidedPrediction out;
  if (keep_raw) out.raw = torch::cat({uncond, cond});
  out.combined = uncond + scale * (cond - uncond);
  return out;
}

torch::Tensor batch_half(const torch::Tensor& doubled, GuidanceHalf half) {
  if (doubled.dim() == 0 || doubled.size(0) % 2 != 0)
    throw Error("guidance: a doubled batch needs an even first dimension, got " + c10::str(doubled.sizes()));
  const int64_t n = doubled.size(0) / 2;
  return doubled.narrow(0, half == GuidanceHalf::kConditional ? n : 0, n);
}

}  // namespace u3d::nn
