// One denoising step of each Unique3D model at its official size, full-size random weights, on the CPU
// with every core:
//  - multi-view (img2mvimg): 4 views at 256 px with guidance, so the UNet sees batch 8 at 32x32 latents
//    with joint attention over the 4 views, class labels and the concatenated condition latents;
//  - normal (image2normal), per view: 512 px with guidance, a reference pass over the condition latents
//    and the main UNet, each batch 2 at 64x64 (the official pipeline batches the 4 views: 4x this).
// Prints seconds per step (median of --repetitions, default 3) and peak RSS. A full run is 30 steps each.
// Usage: bench_unique3d_steps [--dtype=fp32|bf16] [--repetitions=N]
#include <sys/resource.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/layers/layers.h"
#include "nn/layers/multiview_attention.h"
#include "nn/models/unet.h"
#include "nn/models/unet_reference.h"
#include "nn/precision.h"
#include "nn/runtime.h"

using namespace u3d::nn;

namespace {

UNetConfig manifest_config(const std::string& name) {
  auto m = read_json_file(std::string(UNIQUE3D_SOURCE_DIR) + "/tests/data/nn/manifests/" + name + ".json");
  return UNetConfig::from_json(m.at("constructor_config"), name);
}

double median_seconds(int repetitions, const std::function<void()>& step) {
  std::vector<double> times;
  for (int i = 0; i < repetitions; ++i) {
    const auto start = std::chrono::steady_clock::now();
    step();
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

double peak_rss_gb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0);
}

}  // namespace

int main(int argc, char** argv) try {
  Precision precision = Precision::kFp32;
  int repetitions = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.starts_with("--dtype="))
      precision = parse_precision(arg.substr(8), "--dtype");
    else if (arg.starts_with("--repetitions="))
      repetitions = std::max(1, std::stoi(arg.substr(14)));
    else
      throw u3d::Error("unknown argument '" + arg + "' (usage: bench_unique3d_steps [--dtype=fp32|bf16] [--repetitions=N])");
  }
  configure_torch_threads();
  at::globalContext().setFlushDenormal(true);  // random weights: keep the FPU off its denormal path
  c10::InferenceMode inference;
  const auto options = torch::TensorOptions().dtype(scalar_type(precision));
  torch::manual_seed(0);

  {
    UNet2DConditionModel unet(manifest_config("unet_unique3d_img2mvimg"), options);
    randomize_parameters(*unet, 0.02);
    set_precision(*unet, precision);
    set_attention_processors(*unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(4)));
    torch::Tensor x = torch::randn({8, 4, 32, 32}), context = torch::randn({8, 1, 768});
    UNetExtras extras;
    extras.class_labels = torch::arange(4, torch::kLong).repeat(2);
    extras.condition_latents = torch::randn({2, 4, 32, 32});
    const double s = median_seconds(repetitions, [&] { unet->forward(x, torch::tensor(500.0f), context, extras); });
    std::printf("multi-view step (batch 8 at 32x32, 4 joint views)  %s: %6.2f s   peak RSS %.2f GB\n",
                precision_name(precision), s, peak_rss_gb());
  }
  {
    ReferenceUNet model(manifest_config("unet_unique3d_image2normal"), options);
    randomize_parameters(*model.unet, 0.02);  // the reference UNet is registered inside it
    set_precision(*model.unet, precision);
    torch::Tensor x = torch::randn({2, 4, 64, 64}), context = torch::randn({2, 1, 768});
    torch::Tensor condition = torch::randn({2, 4, 64, 64});
    const double s = median_seconds(repetitions, [&] { model.forward(x, torch::tensor(500.0f), context, condition); });
    std::printf("normal step per view (reference + main, batch 2 at 64x64) %s: %6.2f s   peak RSS %.2f GB\n",
                precision_name(precision), s, peak_rss_gb());
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_unique3d_steps: %s\n", e.what());
  return 1;
}
