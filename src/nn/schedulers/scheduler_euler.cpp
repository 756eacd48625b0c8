#include "nn/schedulers/scheduler_euler.h"

namespace u3d::nn {

EulerScheduler::EulerScheduler(const SchedulerConfig& config) : SigmaScheduler(config, "EulerDiscreteScheduler") {}

SchedulerStep EulerScheduler::step(const torch::Tensor& model_output, int step_index, const torch::Tensor& sample_in,
                                   NoiseSource& noise) {
  check_step_index(step_index);
  const torch::Tensor sample = sample_in.to(torch::kFloat32);
  const torch::Tensor sigma = sigmas_[step_index];
  noise.randn(model_output.sizes(), model_output.scalar_type());  // unused without churn; keeps the stream aligned
  // Without churn diffusers' sigma_hat = sigma * (gamma + 1) is sigma itself.
  const torch::Tensor pred_original = predict_original(model_output, sample, sigma);
  const torch::Tensor derivative = (sample - pred_original) / sigma;
  const torch::Tensor prev = sample + derivative * (sigmas_[step_index + 1] - sigma);
  return {prev.to(model_output.scalar_type()), pred_original};
}

}  // namespace u3d::nn
