#pragma once
// The diffusers scheduler_config.json, as read by every scheduler here. Keys a scheduler does not use
// are ignored (as diffusers does when a config is loaded into another scheduler class, e.g. the
// PNDMScheduler config of sd-image-variations loaded into EulerAncestralDiscreteScheduler).
// Options this port does not implement are refused when a scheduler is built from the config, never
// silently ignored.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace u3d::nn {

struct SchedulerConfig {
  std::string class_name;  // "_class_name" as written; may name another scheduler class
  int num_train_timesteps = 1000;
  double beta_start = 0.0001;
  double beta_end = 0.02;
  std::string beta_schedule = "linear";  // linear | scaled_linear | squaredcos_cap_v2
  std::vector<double> trained_betas;     // non-empty: used instead of beta_schedule
  std::string prediction_type = "epsilon";
  std::optional<std::string> timestep_spacing;  // unset: the scheduler class's own default
  int steps_offset = 0;
  // DDIM only.
  bool set_alpha_to_one = true;
  bool clip_sample = true;
  double clip_sample_range = 1.0;
  // Not implemented here; a config that turns them on is refused.
  bool thresholding = false;
  bool rescale_betas_zero_snr = false;
  bool use_karras_sigmas = false;
  std::string interpolation_type = "linear";
  std::string timestep_type = "discrete";

  std::string source = "scheduler config";  // names the config in errors
};

// Parses a scheduler config; wrong value types are u3d::Error naming `source` and the key.
SchedulerConfig parse_scheduler_config(const nlohmann::json& json, const std::string& source);
SchedulerConfig read_scheduler_config(const std::filesystem::path& path);

}  // namespace u3d::nn
