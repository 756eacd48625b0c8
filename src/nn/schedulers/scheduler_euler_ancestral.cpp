#include "nn/schedulers/scheduler_euler_ancestral.h"

namespace u3d::nn {

EulerAncestralScheduler::EulerAncestralScheduler(const SchedulerConfig& config)
    : SigmaScheduler(config, "EulerAncestralDiscreteScheduler") {}

SchedulerStep EulerAncestralScheduler::step(const torch::Tensor& model_output, int step_index,
                                            const torch::Tensor& sample_in, NoiseSource& noise) {
  check_step_index(step_index);
  const torch::Tensor sample = sample_in.to(torch::kFloat32);
  const torch::Tensor sigma = sigmas_[step_index];
  const torch::Tensor pred_original = predict_original(model_output, sample, sigma);

  const torch::Tensor sigma_to = sigmas_[step_index + 1];
  const torch::Tensor sigma_up = (sigma_to.pow(2) * (sigma.pow(2) - sigma_to.pow(2)) / sigma.pow(2)).pow(0.5);
  const torch::Tensor sigma_down = (sigma_to.pow(2) - sigma_up.pow(2)).pow(0.5);

  const torch::Tensor derivative = (sample - pred_original) / sigma;
  torch::Tensor prev = sample + derivative * (sigma_down - sigma);
  prev = prev + noise.randn(model_output.sizes(), model_output.scalar_type()) * sigma_up;
  return {prev.to(model_output.scalar_type()), pred_original};
}

}  // namespace u3d::nn
