#include "nn/schedulers/scheduler_sigma_base.h"

#include "core/error.h"

namespace u3d::nn {

SigmaScheduler::SigmaScheduler(const SchedulerConfig& config, const std::string& name)
    : config_(config), spacing_(timestep_spacing(config, TimestepSpacing::Linspace)) {
  check_supported_options(config, name);
  require(config.prediction_type == "epsilon" || config.prediction_type == "v_prediction",
          config.source + ": prediction_type '" + config.prediction_type + "' is not supported by " + name +
              " (expected epsilon or v_prediction)");
  alphas_cumprod_ = make_alphas_cumprod(config);
}

void SigmaScheduler::set_timesteps(int num_inference_steps) {
  const std::vector<double> t = spaced_timesteps(config_, spacing_, num_inference_steps);
  timesteps_ = torch::tensor(t, torch::kFloat64).to(torch::kFloat32);
  sigmas_ = interpolated_sigmas(alphas_cumprod_, timesteps_);
}

torch::Tensor SigmaScheduler::init_noise_sigma() const {
  require(sigmas_.defined(), name() + ": set_timesteps was not called");
  const torch::Tensor max_sigma = sigmas_.max();
  if (spacing_ == TimestepSpacing::Leading) return (max_sigma.pow(2) + 1).pow(0.5);
  return max_sigma;
}

torch::Tensor SigmaScheduler::scale_model_input(const torch::Tensor& sample, int step_index) const {
  check_step_index(step_index);
  const torch::Tensor sigma = sigmas_[step_index];
  return sample / (sigma.pow(2) + 1).pow(0.5);
}

torch::Tensor SigmaScheduler::add_noise(const torch::Tensor& original, const torch::Tensor& noise,
                                        int step_index) const {
  check_step_index(step_index);
  return original + noise * sigmas_[step_index].to(original.scalar_type());
}

torch::Tensor SigmaScheduler::predict_original(const torch::Tensor& model_output, const torch::Tensor& sample,
                                               const torch::Tensor& sigma) const {
  if (config_.prediction_type == "epsilon") return sample - sigma * model_output;
  // v_prediction: c_out * v + c_skip * x
  return model_output * (-sigma / (sigma.pow(2) + 1).pow(0.5)) + sample / (sigma.pow(2) + 1);
}

}  // namespace u3d::nn
