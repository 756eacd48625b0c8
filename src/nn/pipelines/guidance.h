#pragma once
// Classifier-free guidance with its two halves run one after the other. The official pipelines (and
// diffusers) run the unconditional and the conditional inputs as one doubled batch and combine the
// halves as uncond + g (cond - uncond); every network here treats the samples of a batch on their own
// (the multi-view attention within each group of four views), so two passes give the same prediction
// with half the activations alive. run_image_diffusion (the multi-view and normal loops) runs this way:
// the normal step is the peak of a whole fp32 run. The refinement keeps the doubled batch: at batch 1
// its step was a quarter slower in fp32 for 0.8 GiB less (docs/networks.md, "Memory").
#include <torch/torch.h>

#include <functional>

namespace u3d::nn {

enum class GuidanceHalf { kUnconditional = 0, kConditional = 1 };

struct GuidedPrediction {
  torch::Tensor combined;  // uncond + scale (cond - uncond)
  torch::Tensor raw;       // [uncond, cond] concatenated as the doubled batch's prediction; only when asked
};

// Runs `predict` for the unconditional half, then the conditional one, and combines them; `keep_raw`
// also returns both halves (for traces that compare with the official doubled batch).
GuidedPrediction guided_prediction(double scale, const std::function<torch::Tensor(GuidanceHalf)>& predict,
                                   bool keep_raw = false);

// The half of a doubled batch [2N, ...] (unconditional first) that `half` names.
torch::Tensor batch_half(const torch::Tensor& doubled, GuidanceHalf half);

}  // namespace u3d::nn
