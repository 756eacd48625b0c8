#include "nn/schedulers/noise_schedule.h"

#include <cmath>

#include "core/error.h"

namespace u3d::nn {
namespace {

// Glide's cosine schedule, as diffusers' betas_for_alpha_bar (computed in float64).
std::vector<double> cosine_betas(int num_train_timesteps) {
  auto alpha_bar = [](double t) { return std::pow(std::cos((t + 0.008) / 1.008 * M_PI / 2), 2); };
  std::vector<double> betas;
  for (int i = 0; i < num_train_timesteps; ++i) {
    const double t1 = double(i) / num_train_timesteps;
    const double t2 = double(i + 1) / num_train_timesteps;
    betas.push_back(std::min(1 - alpha_bar(t2) / alpha_bar(t1), 0.999));
  }
  return betas;
}

torch::Tensor float32_tensor(const std::vector<double>& values) {
  return torch::tensor(values, torch::kFloat64).to(torch::kFloat32);
}

// numpy.interp(x, [0, 1, ..., n-1], table) for x inside [0, n-1]: slope * (x - j) + table[j].
double interp_on_grid(double x, const std::vector<double>& table) {
  const int n = int(table.size());
  if (x <= 0) return table.front();
  if (x >= n - 1) return table.back();
  const int j = int(std::floor(x));
  if (double(j) == x) return table[j];
  const double slope = (table[j + 1] - table[j]) / double((j + 1) - j);
  return slope * (x - double(j)) + table[j];
}

}  // namespace

torch::Tensor make_alphas_cumprod(const SchedulerConfig& c) {
  const int64_t T = c.num_train_timesteps;
  torch::Tensor betas;
  if (!c.trained_betas.empty()) {
    betas = float32_tensor(c.trained_betas);
  } else if (c.beta_schedule == "linear") {
    betas = torch::linspace(c.beta_start, c.beta_end, T, torch::kFloat32);
  } else if (c.beta_schedule == "scaled_linear") {
    betas = torch::linspace(std::pow(c.beta_start, 0.5), std::pow(c.beta_end, 0.5), T, torch::kFloat32).pow(2);
  } else if (c.beta_schedule == "squaredcos_cap_v2") {
    betas = float32_tensor(cosine_betas(int(T)));
  } else {
    throw Error(c.source + ": unknown beta_schedule '" + c.beta_schedule +
                "' (expected linear, scaled_linear or squaredcos_cap_v2)");
  }
  return torch::cumprod(1.0 - betas, 0);
}

TimestepSpacing timestep_spacing(const SchedulerConfig& c, TimestepSpacing fallback) {
  if (!c.timestep_spacing) return fallback;
  if (*c.timestep_spacing == "linspace") return TimestepSpacing::Linspace;
  if (*c.timestep_spacing == "leading") return TimestepSpacing::Leading;
  if (*c.timestep_spacing == "trailing") return TimestepSpacing::Trailing;
  throw Error(c.source + ": unknown timestep_spacing '" + *c.timestep_spacing +
              "' (expected linspace, leading or trailing)");
}

std::vector<double> spaced_timesteps(const SchedulerConfig& c, TimestepSpacing spacing, int n) {
  const int T = c.num_train_timesteps;
  require(n >= 1 && n <= T, "number of inference steps " + std::to_string(n) + " must be in [1, " +
                                std::to_string(T) + "] (num_train_timesteps of " + c.source + ")");
  std::vector<double> t;
  switch (spacing) {
    case TimestepSpacing::Linspace: {
      // numpy.linspace: i * step + start, with the endpoint set exactly.
      const double step = n > 1 ? double(T - 1) / double(n - 1) : 0.0;
      for (int i = 0; i < n; ++i) t.push_back(double(i) * step);
      if (n > 1) t.back() = double(T - 1);
      break;
    }
    case TimestepSpacing::Leading: {
      const int ratio = T / n;
      for (int i = 0; i < n; ++i) t.push_back(double(i * ratio + c.steps_offset));
      break;
    }
    case TimestepSpacing::Trailing: {
      // numpy.arange(T, 0, -T/n): length ceil(-T / step); element i = start + i * (a[1] - a[0]).
      const double step = -double(T) / double(n);
      const auto length = int64_t(std::ceil((0.0 - double(T)) / step));
      const double delta = (double(T) + step) - double(T);
      for (int64_t i = 0; i < length; ++i) {
        const double value = i == 0 ? double(T) : double(T) + double(i) * delta;
        t.push_back(std::nearbyint(value) - 1.0);  // numpy rounds half to even, as nearbyint does
      }
      return t;  // already highest first
    }
  }
  return {t.rbegin(), t.rend()};
}

torch::Tensor interpolated_sigmas(const torch::Tensor& alphas_cumprod, const torch::Tensor& timesteps) {
  // diffusers computes this table with float32 torch ops, then numpy.interp works in float64.
  const torch::Tensor table32 = ((1 - alphas_cumprod) / alphas_cumprod).pow(0.5).contiguous();
  const std::vector<double> table(table32.data_ptr<float>(), table32.data_ptr<float>() + table32.numel());
  const torch::Tensor ts = timesteps.to(torch::kFloat64).contiguous();
  std::vector<double> sigmas;
  for (int64_t i = 0; i < ts.numel(); ++i) sigmas.push_back(interp_on_grid(ts.data_ptr<double>()[i], table));
  sigmas.push_back(0.0);
  return float32_tensor(sigmas);
}

void check_supported_options(const SchedulerConfig& c, const std::string& name) {
  auto refuse = [&](const std::string& what) {
    throw Error(c.source + ": " + what + " is not supported by the " + name + " port");
  };
  if (c.thresholding) refuse("thresholding");
  if (c.rescale_betas_zero_snr) refuse("rescale_betas_zero_snr");
  if (c.use_karras_sigmas) refuse("use_karras_sigmas");
  if (c.interpolation_type != "linear") refuse("interpolation_type '" + c.interpolation_type + "'");
  if (c.timestep_type != "discrete") refuse("timestep_type '" + c.timestep_type + "'");
}

}  // namespace u3d::nn
