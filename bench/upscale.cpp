// Full-size Real-ESRGAN x4 (RRDBNet 64 features, 23 blocks, growth 32; random weights) upscaling one
// SIZE x SIZE RGB image by 4 with the upscaler's tiling (UpscaleModel::upscale), on the CPU with every core.
// Prints the time, the tile count and the process's peak resident memory (one upscale per run).
// Not a Google Benchmark: a 512 -> 2048 upscale takes minutes.
// Usage: bench_upscale [--dtype=fp32|bf16] [--size=512] [--tile=256] (tile 0: the whole image at once)
#include <sys/resource.h>
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "core/progress.h"
#include "nn/layers/layers.h"
#include "nn/pipelines/upscale.h"
#include "nn/precision.h"
#include "nn/runtime.h"

using namespace u3d::nn;

int main(int argc, char** argv) try {
  Precision precision = Precision::kFp32;
  int64_t size = 512, tile = kDefaultTile;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.starts_with("--dtype="))
      precision = parse_precision(arg.substr(8), "--dtype");
    else if (arg.starts_with("--size="))
      size = std::stoll(arg.substr(7));
    else if (arg.starts_with("--tile="))
      tile = std::stoll(arg.substr(7));
    else
      throw u3d::Error("unknown argument '" + arg +
                       "' (usage: bench_upscale [--dtype=fp32|bf16] [--size=512] [--tile=256])");
  }
  if (size <= 0) throw u3d::Error("--size must be positive");
  configure_torch_threads();
  at::globalContext().setFlushDenormal(true);  // random weights: keep the FPU off its denormal path
  u3d::set_progress_quiet(true);
  c10::InferenceMode inference;
  UpscaleModel model;
  model.net = RRDBNet(RRDBNetConfig{}, torch::TensorOptions());
  torch::manual_seed(0);
  randomize_parameters(*model.net, 0.02);
  set_precision(*model.net, precision);
  model.tile = tile;

  const torch::Tensor image = torch::randint(0, 256, {size, size, 3}, torch::kUInt8);
  const int64_t per_side = tile <= 0 || size <= tile ? 1 : (size + tile - 1) / tile;
  const auto start = std::chrono::steady_clock::now();
  const torch::Tensor out = model.upscale(image);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("RRDBNet x4 %s: %lld -> %lld x %lld, %lld tiles of %lld px (+%lld context), %.1f s, peak RSS %.2f GB\n",
              precision_name(precision), static_cast<long long>(size), static_cast<long long>(out.size(0)),
              static_cast<long long>(out.size(1)), static_cast<long long>(per_side * per_side),
              static_cast<long long>(per_side == 1 ? size : tile), static_cast<long long>(per_side == 1 ? 0 : kTilePad),
              seconds, static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0));
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_upscale: %s\n", e.what());
  return 1;
}
