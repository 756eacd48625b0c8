// Full-size SD 1.x VAE (tests/data/nn/manifests/vae_sd1x.json, random weights) decoding one latent into a
// SIZE x SIZE image in tiles (AutoencoderKL::decode_tiled with the config's default tiling; --op=tiled),
// decoding it whole (--op=decode) or encoding a SIZE x SIZE image whole (--op=encode, as the refinement
// encodes its 1024 px grid), on the CPU with every core. Prints the time, the tile count and the
// process's peak resident memory, which is this operation's alone plus the weights (one per run). Not a
// Google Benchmark: a 2048 px decode takes minutes.
// Usage: bench_vae [--dtype=fp32|bf16] [--size=2048] [--op=tiled|decode|encode]
#include <sys/resource.h>
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/layers/layers.h"
#include "nn/models/vae.h"
#include "nn/precision.h"
#include "nn/runtime.h"

using namespace u3d::nn;

int main(int argc, char** argv) try {
  Precision precision = Precision::kFp32;
  int64_t size = 2048;
  std::string op = "tiled";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.starts_with("--dtype="))
      precision = parse_precision(arg.substr(8), "--dtype");
    else if (arg.starts_with("--size="))
      size = std::stoll(arg.substr(7));
    else if (arg.starts_with("--op=") && (arg == "--op=tiled" || arg == "--op=decode" || arg == "--op=encode"))
      op = arg.substr(5);
    else
      throw u3d::Error("unknown argument '" + arg +
                       "' (usage: bench_vae [--dtype=fp32|bf16] [--size=2048] [--op=tiled|decode|encode])");
  }
  configure_torch_threads();
  at::globalContext().setFlushDenormal(true);  // random weights: keep the FPU off its denormal path
  c10::InferenceMode inference;
  auto manifest = read_json_file(std::string(UNIQUE3D_SOURCE_DIR) + "/tests/data/nn/manifests/vae_sd1x.json");
  const auto config = AutoencoderKLConfig::from_json(manifest.at("constructor_config"), "vae manifest");
  if (size <= 0 || size % config.scale_factor() != 0)
    throw u3d::Error("--size must be a positive multiple of " + std::to_string(config.scale_factor()));
  AutoencoderKL vae(config, torch::TensorOptions().dtype(scalar_type(precision)));
  torch::manual_seed(0);
  randomize_parameters(*vae, 0.02);
  set_precision(*vae, precision);

  const int64_t latent_side = size / config.scale_factor();
  torch::Tensor latent = torch::randn({1, config.latent_channels, latent_side, latent_side});
  const VaeTiling tiling = vae->default_tiling();
  const int64_t stride = static_cast<int64_t>(tiling.tile_latent * (1.0 - tiling.overlap));
  const int64_t per_side = latent_side <= tiling.tile_latent ? 1 : (latent_side + stride - 1) / stride;

  const auto start = std::chrono::steady_clock::now();
  torch::Tensor out;
  if (op == "encode")
    out = vae->encode(torch::rand({1, config.in_channels, size, size}) * 2 - 1).mean;
  else
    out = op == "decode" ? vae->decode(latent) : vae->decode_tiled(latent, tiling);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const long long tiles = op == "tiled" ? per_side * per_side : 1;
  const long long tile_px = op == "tiled" ? tiling.tile_latent * config.scale_factor() : size;
  std::printf("VAE %s %s: %lld px, output %s, %lld tiles of %lld px, %.1f s, peak RSS %.2f GB (%s, %s)\n", op.c_str(),
              precision_name(precision), static_cast<long long>(size), c10::str(out.sizes()).c_str(), tiles, tile_px,
              seconds, static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0), c10::toString(out.scalar_type()),
              out.isfinite().all().item<bool>() ? "finite" : "NOT finite");
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_vae: %s\n", e.what());
  return 1;
}
