#pragma once
// DDIM sampling (diffusers DDIMScheduler; default spacing 'leading'). eta = 0 gives the deterministic
// sampler; eta > 0 adds noise drawn from the NoiseSource.
#include "nn/schedulers/noise_schedule.h"
#include "nn/schedulers/scheduler.h"

namespace u3d::nn {

class DdimScheduler : public Scheduler {
 public:
  explicit DdimScheduler(const SchedulerConfig& config, double eta = 0.0);
  std::string name() const override { return "DDIMScheduler"; }
  void set_timesteps(int num_inference_steps) override;
  torch::Tensor init_noise_sigma() const override;
  // DDIM needs no input scaling: returns `sample`.
  torch::Tensor scale_model_input(const torch::Tensor& sample, int step_index) const override;
  SchedulerStep step(const torch::Tensor& model_output, int step_index, const torch::Tensor& sample,
                     NoiseSource& noise) override;

 private:
  SchedulerConfig config_;
  TimestepSpacing spacing_;
  double eta_;
  int num_inference_steps_ = 0;
  torch::Tensor final_alpha_cumprod_;  // alpha_cumprod "before" timestep 0
};

}  // namespace u3d::nn
