// `generate` end to end at the official sizes and defaults with random weights: writes a model folder in
// the official layout with every network at full size and random weights once (bench/random_models.h,
// cached, ~11 GB), then runs the library's generate() on a bundled photo and prints each stage's time
// and its own peak memory (the process's, from the stage's start). The mesh is nonsense; the work is real.
// Usage: bench_pipeline [--models DIR] [--photo PNG] [--dtype auto|fp32|bf16] [--steps N] [--refine-steps N]
//                       [--no-refine] [--keep DIR] [--write-only]
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/error.h"
#include "core/progress.h"
#include "nn/runtime.h"
#include "pipeline/generate.h"
#include "random_models.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) try {
  using namespace u3d;
  const char* home = std::getenv("HOME");
  std::string models = (fs::path(home ? home : "/tmp") / ".cache" / "unique3d" / "random-models").string();
  std::string photo = (fs::path(UNIQUE3D_SOURCE_DIR) / "tests" / "data" / "nn" / "photos" / "ex2.png").string();
  std::string dtype = "auto", keep;
  int steps = 0, refine_steps = 0;
  bool no_refine = false, write_only = false;
  CLI::App app{"Times unique3d generate at full size with random weights"};
  app.add_option("--models", models, "Where the random model folder is (written when incomplete)")->capture_default_str();
  app.add_option("--photo", photo, "The photo")->capture_default_str();
  app.add_option("--dtype", dtype, "auto, fp32 or bf16")->capture_default_str();
  app.add_option("--steps", steps, "Denoising steps of the multi-view and normal models (default: official, 30)");
  app.add_option("--refine-steps", refine_steps,
                 "The refinement's schedule length (default: official, 50; strength 0.2 runs the last fifth)");
  app.add_flag("--no-refine", no_refine, "Skip the refinement (as generate --no-refine)");
  app.add_option("--keep", keep, "Keep the intermediates in this folder");
  app.add_flag("--write-only", write_only, "Only write the model folder");
  CLI11_PARSE(app, argc, argv);

  nn::configure_torch_threads();
  bench::write_random_model_folder(models);
  if (write_only) return 0;

  const fs::path out = fs::temp_directory_path() / "bench_pipeline";
  fs::create_directories(out);
  GenerateRequest request;
  request.image = photo;
  request.output = out / "mesh.glb";
  request.network.models = models;
  if (dtype != "auto") request.network.precision = nn::parse_precision(dtype, "--dtype");
  request.refine = !no_refine;
  request.keep_intermediates = keep;
  if (steps > 0) request.multiview.steps = request.normals.steps = steps;
  if (refine_steps > 0) request.refine_options.steps = refine_steps;
  StderrProgress progress(false);
  const GenerateSummary summary = generate(request, &progress);
  std::printf("bench_pipeline: %s, %d threads, %d multi-view and normal steps, %d refinement schedule steps\n",
              nn::precision_name(summary.precision), at::get_num_threads(), request.multiview.steps,
              request.refine ? request.refine_options.steps : 0);
  std::printf("%-12s %10s %18s\n", "stage", "seconds", "peak memory MiB");
  for (const GenerateStageReport& stage : summary.stages)
    std::printf("%-12s %10.1f %18.0f\n", stage.name.c_str(), stage.seconds, stage.peak_memory_mib);
  std::printf("%-12s %10.1f %18.0f  (the process's peak, as /usr/bin/time -v reports it)\n", "total",
              summary.total_seconds(), summary.peak_memory_mib);
  return 0;
} catch (const u3d::Error& e) {
  std::fprintf(stderr, "bench_pipeline: error: %s\n", e.what());
  return 1;
}
