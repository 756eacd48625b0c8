#include "nn/schedulers/scheduler_config.h"

#include <fstream>

#include "core/error.h"

namespace u3d::nn {
namespace {

// Reads json[key] into `out` when present and not null; a value of the wrong type is an error.
template <class T>
void read_key(const nlohmann::json& json, const char* key, T& out, const std::string& source) {
  auto it = json.find(key);
  if (it == json.end() || it->is_null()) return;
  try {
    if constexpr (std::is_same_v<T, int>) {
      require(it->is_number_integer(), "not an integer");
    } else if constexpr (std::is_same_v<T, double>) {
      require(it->is_number(), "not a number");
    } else if constexpr (std::is_same_v<T, bool>) {
      require(it->is_boolean(), "not a boolean");
    } else if constexpr (std::is_same_v<T, std::string>) {
      require(it->is_string(), "not a string");
    }
    out = it->get<T>();
  } catch (const std::exception& e) {
    throw Error(source + ": key '" + key + "' has a wrong value " + it->dump() + " (" + e.what() + ")");
  }
}

}  // namespace

SchedulerConfig parse_scheduler_config(const nlohmann::json& json, const std::string& source) {
  require(json.is_object(), source + ": a scheduler config must be a JSON object");
  SchedulerConfig c;
  c.source = source;
  read_key(json, "_class_name", c.class_name, source);
  read_key(json, "num_train_timesteps", c.num_train_timesteps, source);
  read_key(json, "beta_start", c.beta_start, source);
  read_key(json, "beta_end", c.beta_end, source);
  read_key(json, "beta_schedule", c.beta_schedule, source);
  read_key(json, "trained_betas", c.trained_betas, source);
  read_key(json, "prediction_type", c.prediction_type, source);
  std::string spacing;
  read_key(json, "timestep_spacing", spacing, source);
  if (!spacing.empty()) c.timestep_spacing = spacing;
  read_key(json, "steps_offset", c.steps_offset, source);
  read_key(json, "set_alpha_to_one", c.set_alpha_to_one, source);
  read_key(json, "clip_sample", c.clip_sample, source);
  read_key(json, "clip_sample_range", c.clip_sample_range, source);
  read_key(json, "thresholding", c.thresholding, source);
  read_key(json, "rescale_betas_zero_snr", c.rescale_betas_zero_snr, source);
  read_key(json, "use_karras_sigmas", c.use_karras_sigmas, source);
  read_key(json, "interpolation_type", c.interpolation_type, source);
  read_key(json, "timestep_type", c.timestep_type, source);
  require(c.num_train_timesteps >= 1, source + ": num_train_timesteps must be positive");
  require(c.trained_betas.empty() || int(c.trained_betas.size()) == c.num_train_timesteps,
          source + ": trained_betas has " + std::to_string(c.trained_betas.size()) + " values, num_train_timesteps is " +
              std::to_string(c.num_train_timesteps));
  return c;
}

SchedulerConfig read_scheduler_config(const std::filesystem::path& path) {
  std::ifstream in(path);
  require(bool(in), "cannot open scheduler config " + path.string());
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(path.string() + ": invalid JSON (" + e.what() + ")");
  }
  return parse_scheduler_config(json, path.string());
}

}  // namespace u3d::nn
