#pragma once
// Helpers for the golden-reference tests (tests/data/nn/<case>/, copied from the Python reference run).
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/checkpoint/tensor_map.h"
#include "nn/schedulers/noise_source.h"

namespace u3d::nn::test {

inline std::filesystem::path golden_dir(const std::string& case_name) {
  return std::filesystem::path(UNIQUE3D_TEST_DATA) / "nn" / case_name;
}

inline TensorMap golden_tensors(const std::string& case_name, const std::string& file) {
  return load_safetensors(golden_dir(case_name) / (file + ".safetensors"));
}

inline nlohmann::json golden_config(const std::string& case_name, const std::string& file = "config.json") {
  return read_json_file(golden_dir(case_name) / file);
}

// Loads <case>/weights.safetensors into `module` with the library's strict loader (nn::load_state_dict):
// every parameter and buffer covered, every tensor used, equal shapes; only `policy` relaxes that.
inline LoadReport load_golden_weights(torch::nn::Module& module, const std::string& case_name,
                                      const LoadPolicy& policy = {}) {
  return load_state_dict(module, golden_tensors(case_name, "weights"), policy, case_name + "/weights.safetensors");
}

inline double max_abs_diff(const torch::Tensor& a, const torch::Tensor& b) {
  EXPECT_EQ(a.sizes(), b.sizes());
  if (a.sizes() != b.sizes()) return INFINITY;
  return (a.to(torch::kDouble) - b.to(torch::kDouble)).abs().max().item<double>();
}

// ||a - b|| / ||b|| over all elements, in float64.
inline double relative_error(const torch::Tensor& a, const torch::Tensor& b) {
  EXPECT_EQ(a.sizes(), b.sizes());
  if (a.sizes() != b.sizes()) return INFINITY;
  const torch::Tensor ref = b.to(torch::kDouble);
  return ((a.to(torch::kDouble) - ref).norm() / ref.norm()).item<double>();
}

// The golden README's acceptance for single fp32 forward passes.
constexpr double kForwardTolerance = 1e-4;

// Copies golden files into a model folder: {golden file, path inside `folder`} pairs.
inline void copy_into_folder(const std::filesystem::path& folder,
                             const std::vector<std::pair<std::filesystem::path, std::string>>& files) {
  for (const auto& [from, to] : files) {
    std::filesystem::create_directories((folder / to).parent_path());
    std::filesystem::copy_file(from, folder / to);
  }
}

// Writes the tiny sd-image-variations stand-in in the diffusers layout: the plain UNet (config and,
// when `unet_weights`, weights), CLIP image encoder, VAE, the 32 px feature extractor and the SD scheduler.
inline void write_image_variations_folder(const std::filesystem::path& folder, bool unet_weights) {
  copy_into_folder(folder, {{golden_dir("unet_base") / "config.json", "unet/config.json"},
                            {golden_dir("clip_vision") / "config.json", "image_encoder/config.json"},
                            {golden_dir("clip_vision") / "weights.safetensors", "image_encoder/model.safetensors"},
                            {golden_dir("vae") / "config.json", "vae/config.json"},
                            {golden_dir("vae") / "weights.safetensors", "vae/diffusion_pytorch_model.safetensors"},
                            {golden_dir("clip_vision") / "preprocessor_config_tiny32.json",
                             "feature_extractor/preprocessor_config.json"},
                            {golden_dir("scheduler") / "sd_scheduler_config.json", "scheduler/scheduler_config.json"}});
  if (unet_weights)
    copy_into_folder(folder, {{golden_dir("unet_base") / "weights.safetensors", "unet/diffusion_pytorch_model.safetensors"}});
}

// Replays a golden pipeline run's noise in the order the pipeline draws it: "pipe.init_noise" first when
// the pipeline draws its initial latents itself, then "pipe.step_noise.0", "pipe.step_noise.1", ...
class GoldenPipelineNoise : public NoiseSource {
 public:
  GoldenPipelineNoise(TensorMap inputs, bool draws_initial_latents)
      : inputs_(std::move(inputs)), initial_(draws_initial_latents) {}
  torch::Tensor randn(at::IntArrayRef shape, torch::ScalarType dtype) override {
    const int step = draws++ - (initial_ ? 1 : 0);
    const std::string key = step < 0 ? "pipe.init_noise" : "pipe.step_noise." + std::to_string(step);
    const torch::Tensor& n = inputs_.at(key);
    EXPECT_EQ(n.sizes(), shape) << key;
    return n.to(dtype);
  }
  int draws = 0;

 private:
  TensorMap inputs_;
  bool initial_;
};

#define EXPECT_CLOSE_TO_GOLDEN(actual, expected, tol)                                  \
  do {                                                                                  \
    double _err = ::u3d::nn::test::max_abs_diff((actual), (expected));                  \
    EXPECT_LE(_err, (tol)) << #actual << " differs from the reference by " << _err;     \
    std::printf("  [golden] %-60s max abs err %.3g\n", #expected, _err);                 \
  } while (0)

#define EXPECT_RELATIVE_TO_GOLDEN(actual, expected, tol)                                \
  do {                                                                                  \
    double _err = ::u3d::nn::test::relative_error((actual), (expected));                \
    EXPECT_LE(_err, (tol)) << #actual << " differs from the reference by " << _err;     \
    std::printf("  [golden] %-60s relative err %.3g\n", #expected, _err);               \
  } while (0)

}  // namespace u3d::nn::test
