// Full-size sd-image-variations UNet forward (860M parameters, random weights), fp32 on the CPU with
// every core: batch 8 at 32x32 latents and batch 2 at 64x64. Reports the median of a few runs (wall time)
// and the process CPU time of all threads.
// Matrix products run in the OpenMP build of OpenBLAS (see the RPATH note in CMakeLists.txt); `ldd
// build/bench/bench_unet | grep blas` shows which build a run loads.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <torch/csrc/autograd/profiler_legacy.h>
#include <torch/torch.h>

#include <memory>

#include <string>
#include <vector>

#include "nn/checkpoint/config_json.h"
#include "nn/layers/layers.h"
#include "nn/models/unet.h"
#include "nn/precision.h"
#include "nn/runtime.h"

namespace {

using namespace u3d::nn;

Precision g_precision = Precision::kFp32;
std::string g_profile_path;  // --profile=FILE: a Chrome trace of the ops of every timed forward

UNet2DConditionModel& full_size_unet() {
  static UNet2DConditionModel unet = [] {
    auto manifest = read_json_file(std::string(UNIQUE3D_SOURCE_DIR) +
                                   "/tests/data/nn/manifests/unet_sd_image_variations_plain.json");
    UNet2DConditionModel m(UNetConfig::from_json(manifest.at("constructor_config"), "unet manifest"),
                           torch::TensorOptions());
    torch::manual_seed(0);
    randomize_parameters(*m, 0.02);
    set_precision(*m, g_precision);
    return m;
  }();
  return unet;
}

void BM_UNetForward(benchmark::State& state) {
  c10::InferenceMode inference;
  const int64_t batch = state.range(0), size = state.range(1);
  UNet2DConditionModel& unet = full_size_unet();
  torch::manual_seed(1);
  torch::Tensor sample = torch::randn({batch, 4, size, size});
  torch::Tensor embedding = torch::randn({batch, 1, 768});
  torch::Tensor timestep = torch::tensor(500.0f);
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  for (auto _ : state) {
    std::unique_ptr<torch::autograd::profiler::RecordProfile> profile;
    if (!g_profile_path.empty()) profile = std::make_unique<torch::autograd::profiler::RecordProfile>(g_profile_path);
    torch::Tensor out = unet->forward(sample, timestep, embedding);
    benchmark::DoNotOptimize(out.data_ptr());
  }
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  state.counters["threads"] = at::get_num_threads();
  state.SetLabel(precision_name(g_precision));
  // Page faults were a large share of the time (freed tensors handed back to the kernel); peak RSS
  // shows what keeping freed memory costs.
  state.counters["minor_faults"] = static_cast<double>(after.ru_minflt - before.ru_minflt);
  state.counters["peak_rss_GB"] = static_cast<double>(after.ru_maxrss) / (1024.0 * 1024.0);
}

BENCHMARK(BM_UNetForward)
    ->ArgNames({"batch", "latent"})
    ->Args({8, 32})
    ->Args({2, 64})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->MeasureProcessCPUTime()  // CPU column = all threads: comparable when the machine is shared
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  u3d::nn::configure_torch_threads();  // every core, and libtorch's fastest kernels
  // Random weights can drive values into denormals, which would measure the FPU's slow path.
  at::globalContext().setFlushDenormal(true);
  // By default three runs, aggregates only (the first run also pays for oneDNN's primitive set-up);
  // the same flags given on the command line come later and win.
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.starts_with("--dtype="))
      g_precision = parse_precision(arg.substr(8), "--dtype");
    else if (arg.starts_with("--profile="))
      g_profile_path = arg.substr(10);
    else
      args.push_back(argv[i]);
  }
  std::string repetitions = "--benchmark_repetitions=3", aggregates = "--benchmark_report_aggregates_only=true";
  args.insert(args.begin() + 1, {repetitions.data(), aggregates.data()});
  int arg_count = static_cast<int>(args.size());
  benchmark::Initialize(&arg_count, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
