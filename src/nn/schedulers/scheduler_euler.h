#pragma once
// Euler sampling (diffusers EulerDiscreteScheduler) without "churn" (s_churn = 0, the default), i.e. a
// deterministic Euler step; it still draws one noise tensor per step, as diffusers does, so a seeded
// run consumes the random stream exactly like the Python one.
#include "nn/schedulers/scheduler_sigma_base.h"

namespace u3d::nn {

class EulerScheduler : public SigmaScheduler {
 public:
  explicit EulerScheduler(const SchedulerConfig& config);
  std::string name() const override { return "EulerDiscreteScheduler"; }
  SchedulerStep step(const torch::Tensor& model_output, int step_index, const torch::Tensor& sample,
                     NoiseSource& noise) override;
};

}  // namespace u3d::nn
