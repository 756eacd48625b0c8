#include "cli/network_options.h"

#include <cstdio>

#include "cli/command.h"

namespace u3d::cli {

NetworkOptions NetworkArgs::resolved() const {
  NetworkOptions o = options;
  if (dtype != "auto") o.precision = nn::parse_precision(dtype, "--dtype");
  return o;
}

void add_raw_matte_flag(CLI::App& sub, bool& raw_matte) {
  sub.add_flag("--raw-matte", raw_matte,
               "Keep the background-removal mask as the network draws it (default: opaque inside the subject's "
               "outline, holes kept; docs/generate.md)");
}

void add_network_options(CLI::App& sub, NetworkArgs& args, bool seeded, bool models_required) {
  sub.add_option("--models", args.options.models,
                 "Folder with the network weights: the official release's ckpt/ folder (docs/models.md)")
      ->required(models_required);
  sub.add_option("--dtype", args.dtype,
                 "Precision of the networks: auto (bf16 on CPUs with avx512_bf16, else fp32), fp32, bf16, or fp16 "
                 "(CUDA only: on the CPU it is refused)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "fp32", "bf16", "fp16"}));
  if (seeded)
    sub.add_option("--seed", args.options.seed, "Seed of the diffusion noise (same seed, same result)")
        ->capture_default_str();
}

void print_stage_summary(const NetworkStageSummary& summary) {
  for (const auto& path : summary.written) std::printf("wrote %s\n", path.string().c_str());
  std::printf("time:");
  for (size_t i = 0; i < summary.timings.size(); ++i)
    std::printf("%s %s %.1f s", i ? "," : "", summary.timings[i].name.c_str(), summary.timings[i].seconds);
  std::printf(", total %.1f s; %s; peak memory %.0f MiB\n", summary.total_seconds(),
              nn::precision_name(summary.precision), summary.peak_memory_mib);
}

}  // namespace u3d::cli
