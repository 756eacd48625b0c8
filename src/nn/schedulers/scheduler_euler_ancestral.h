#pragma once
// Euler ancestral sampling (diffusers EulerAncestralDiscreteScheduler, k-diffusion's sample_euler_ancestral):
// the sampler Unique3D's multi-view and normal pipelines use.
#include "nn/schedulers/scheduler_sigma_base.h"

namespace u3d::nn {

class EulerAncestralScheduler : public SigmaScheduler {
 public:
  explicit EulerAncestralScheduler(const SchedulerConfig& config);
  std::string name() const override { return "EulerAncestralDiscreteScheduler"; }
  // Deterministic Euler step to sigma_down, then fresh noise * sigma_up (one draw per step).
  SchedulerStep step(const torch::Tensor& model_output, int step_index, const torch::Tensor& sample,
                     NoiseSource& noise) override;
};

}  // namespace u3d::nn
