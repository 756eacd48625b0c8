#pragma once
// Pieces shared by the schedulers: the training noise schedule (betas, alphas_cumprod), the inference
// timestep spacings and the Euler sigma table, each computed the way diffusers 0.27 / numpy do
// (so that tables match the Python reference exactly).
#include <torch/torch.h>

#include <string>
#include <vector>

#include "nn/schedulers/scheduler_config.h"

namespace u3d::nn {

// float32 [num_train_timesteps]: betas from trained_betas or beta_schedule, then cumprod(1 - betas).
torch::Tensor make_alphas_cumprod(const SchedulerConfig& config);

enum class TimestepSpacing { Linspace, Leading, Trailing };

// `config.timestep_spacing`, or `fallback` (the scheduler class's default) when it is unset.
TimestepSpacing timestep_spacing(const SchedulerConfig& config, TimestepSpacing fallback);

// Inference timesteps, highest first, in float64 before the scheduler casts them:
//  linspace: numpy linspace(0, T-1, n), not rounded;
//  leading:  round(i * (T // n)) + steps_offset;
//  trailing: round(numpy arange(T, 0, -T/n)) - 1.
std::vector<double> spaced_timesteps(const SchedulerConfig& config, TimestepSpacing spacing, int num_inference_steps);

// Euler sigmas: sqrt((1 - a) / a) over the training steps, linearly interpolated (numpy.interp) at the
// float32 `timesteps`, a trailing 0 appended, cast to float32: [n + 1].
torch::Tensor interpolated_sigmas(const torch::Tensor& alphas_cumprod, const torch::Tensor& timesteps);

// Refuses options of `config` the schedulers here do not implement.
void check_supported_options(const SchedulerConfig& config, const std::string& scheduler_name);

}  // namespace u3d::nn
