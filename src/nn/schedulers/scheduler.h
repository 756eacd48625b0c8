#pragma once
// The diffusion samplers (diffusers' schedulers), behind one interface the pipelines drive:
//
//   scheduler->set_timesteps(steps);
//   latents = noise.randn(shape) * scheduler->init_noise_sigma();
//   for (int i = 0; i < scheduler->num_steps(); ++i) {
//     auto eps = unet(scheduler->scale_model_input(latents, i), scheduler->timestep(i), ...);
//     latents = scheduler->step(eps, i, latents, noise).prev_sample;
//   }
//
// Steps are addressed by index into the schedule (diffusers looks the timestep value up instead; for a
// full denoising loop the two are the same). The arithmetic mirrors diffusers 0.27 operation by
// operation (float64 schedule tables cast to float32, float32 0-dim tensors in the step), so results
// match the Python reference to the last bit or nearly.
#include <torch/torch.h>

#include <memory>
#include <optional>
#include <string>

#include "nn/schedulers/noise_source.h"
#include "nn/schedulers/scheduler_config.h"

namespace u3d::nn {

struct SchedulerStep {
  torch::Tensor prev_sample;
  torch::Tensor pred_original_sample;
};

class Scheduler {
 public:
  virtual ~Scheduler() = default;
  virtual std::string name() const = 0;

  // Builds the schedule for `num_inference_steps` denoising steps.
  virtual void set_timesteps(int num_inference_steps) = 0;
  int num_steps() const { return int(timesteps_.size(0)); }
  // The whole schedule, highest noise first: float32 for the Euler samplers, int64 for DDIM.
  const torch::Tensor& timesteps() const { return timesteps_; }
  // The UNet's timestep input at step i (0-dim; fractional for Euler with 'linspace' spacing).
  torch::Tensor timestep(int step_index) const;
  // float32 cumulative products of (1 - beta) over the training timesteps.
  const torch::Tensor& alphas_cumprod() const { return alphas_cumprod_; }

  // 0-dim float32 factor for the initial N(0,1) latents.
  virtual torch::Tensor init_noise_sigma() const = 0;
  // The UNet input for step i.
  virtual torch::Tensor scale_model_input(const torch::Tensor& sample, int step_index) const = 0;
  // One denoising step from the model output at step i. Draws from `noise` when the sampler needs it.
  virtual SchedulerStep step(const torch::Tensor& model_output, int step_index, const torch::Tensor& sample,
                             NoiseSource& noise) = 0;

 protected:
  void check_step_index(int step_index) const;
  torch::Tensor timesteps_;  // empty until set_timesteps
  torch::Tensor alphas_cumprod_;
};

enum class SchedulerKind { EulerAncestral, Euler, Ddim };

// "EulerAncestralDiscreteScheduler" -> EulerAncestral, ...; nullopt for classes not implemented here.
std::optional<SchedulerKind> scheduler_kind_from_class_name(const std::string& class_name);

// Builds the scheduler `kind` from `config` (diffusers' Scheduler.from_config). Without `kind`, the
// config's _class_name decides; an unimplemented class or option is a u3d::Error naming the config.
std::unique_ptr<Scheduler> make_scheduler(const SchedulerConfig& config, std::optional<SchedulerKind> kind = {});

}  // namespace u3d::nn
