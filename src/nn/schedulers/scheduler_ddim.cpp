#include "nn/schedulers/scheduler_ddim.h"

#include <cmath>

#include "core/error.h"

namespace u3d::nn {

DdimScheduler::DdimScheduler(const SchedulerConfig& config, double eta)
    : config_(config), spacing_(timestep_spacing(config, TimestepSpacing::Leading)), eta_(eta) {
  check_supported_options(config, name());
  require(config.prediction_type == "epsilon" || config.prediction_type == "sample" ||
              config.prediction_type == "v_prediction",
          config.source + ": prediction_type '" + config.prediction_type + "' is not supported by DDIMScheduler");
  require(eta >= 0, "DDIM eta must be >= 0, got " + std::to_string(eta));
  alphas_cumprod_ = make_alphas_cumprod(config);
  final_alpha_cumprod_ = config.set_alpha_to_one ? torch::tensor(1.0f) : alphas_cumprod_[0];
}

void DdimScheduler::set_timesteps(int num_inference_steps) {
  std::vector<double> t = spaced_timesteps(config_, spacing_, num_inference_steps);
  std::vector<int64_t> ints;
  for (double v : t) ints.push_back(int64_t(std::nearbyint(v)));  // 'linspace' is rounded half to even
  timesteps_ = torch::tensor(ints, torch::kInt64);
  num_inference_steps_ = num_inference_steps;
}

torch::Tensor DdimScheduler::init_noise_sigma() const { return torch::tensor(1.0f); }

torch::Tensor DdimScheduler::scale_model_input(const torch::Tensor& sample, int step_index) const {
  check_step_index(step_index);
  return sample;
}

SchedulerStep DdimScheduler::step(const torch::Tensor& model_output, int step_index, const torch::Tensor& sample,
                                  NoiseSource& noise) {
  check_step_index(step_index);
  const torch::Tensor t = timesteps_[step_index];
  const torch::Tensor prev_t = t - config_.num_train_timesteps / num_inference_steps_;
  const torch::Tensor alpha_t = alphas_cumprod_[t.item<int64_t>()];
  const torch::Tensor alpha_prev = prev_t.item<int64_t>() >= 0 ? alphas_cumprod_[prev_t.item<int64_t>()] : final_alpha_cumprod_;
  const torch::Tensor beta_t = 1 - alpha_t;

  torch::Tensor pred_original, pred_epsilon;
  if (config_.prediction_type == "epsilon") {
    pred_original = (sample - beta_t.pow(0.5) * model_output) / alpha_t.pow(0.5);
    pred_epsilon = model_output;
  } else if (config_.prediction_type == "sample") {
    pred_original = model_output;
    pred_epsilon = (sample - alpha_t.pow(0.5) * pred_original) / beta_t.pow(0.5);
  } else {  // v_prediction
    pred_original = alpha_t.pow(0.5) * sample - beta_t.pow(0.5) * model_output;
    pred_epsilon = alpha_t.pow(0.5) * model_output + beta_t.pow(0.5) * sample;
  }
  if (config_.clip_sample) {
    pred_original = pred_original.clamp(-config_.clip_sample_range, config_.clip_sample_range);
  }

  // sigma_t of the DDIM paper (eq. 16), scaled by eta.
  const torch::Tensor variance = ((1 - alpha_prev) / beta_t) * (1 - alpha_t / alpha_prev);
  const torch::Tensor std_dev = eta_ * variance.pow(0.5);
  const torch::Tensor direction = (1 - alpha_prev - std_dev.pow(2)).pow(0.5) * pred_epsilon;
  torch::Tensor prev = alpha_prev.pow(0.5) * pred_original + direction;
  if (eta_ > 0) prev = prev + std_dev * noise.randn(model_output.sizes(), model_output.scalar_type());
  return {prev, pred_original};
}

}  // namespace u3d::nn
