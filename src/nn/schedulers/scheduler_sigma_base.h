#pragma once
// What the Euler samplers share (diffusers' EulerDiscrete and EulerAncestralDiscrete): the sigma
// table, the initial noise scale and the input scaling x / sqrt(sigma^2 + 1). Default spacing linspace.
#include "nn/schedulers/noise_schedule.h"
#include "nn/schedulers/scheduler.h"

namespace u3d::nn {

class SigmaScheduler : public Scheduler {
 public:
  void set_timesteps(int num_inference_steps) override;
  torch::Tensor init_noise_sigma() const override;
  torch::Tensor scale_model_input(const torch::Tensor& sample, int step_index) const override;
  // float32 [num_steps + 1], the last one 0.
  const torch::Tensor& sigmas() const { return sigmas_; }
  // diffusers' add_noise for a run that starts at step `step_index` (img2img): original + noise * sigma.
  torch::Tensor add_noise(const torch::Tensor& original, const torch::Tensor& noise, int step_index) const;

 protected:
  SigmaScheduler(const SchedulerConfig& config, const std::string& name);
  // The model's estimate of the clean sample at noise level sigma.
  torch::Tensor predict_original(const torch::Tensor& model_output, const torch::Tensor& sample,
                                 const torch::Tensor& sigma) const;

  SchedulerConfig config_;
  TimestepSpacing spacing_;
  torch::Tensor sigmas_;
};

}  // namespace u3d::nn
