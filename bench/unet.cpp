// Full-size sd-image-variations UNet forward (860M parameters, random weights) on the CPU with every
// core: batch 8 at 32x32 latents (a multi-view step) and batch 2 at 64x64 (a normal-map step). Reports
// the median of a few runs (wall time), the process CPU time of all threads and peak RSS.
//   --dtype=fp32|bf16   precision of the model (nn/precision.h); without it both run, each in a child
//                       process (bf16 only on CPUs with avx512_bf16)
//   --check             build in fp32, keep each case's fp32 output, convert, and report rel_err_vs_fp32
//                       (||out - fp32|| / ||fp32||); peak RSS then includes the fp32 model, and the
//                       convolution weights are not packed in place (a second copy, docs/networks.md)
//   --profile=FILE      write a Chrome trace of the ATen ops of the timed forwards
// bench/unet_reference.py times the same cases with diffusers for comparison.
// fp32 linear layers run in oneDNN on CPUs with AVX-512 (nn/layers/onednn_linear.h); other fp32 matrix
// products run in the OpenMP build of OpenBLAS (see the RPATH note in CMakeLists.txt); `ldd
// build/bench/bench_unet | grep blas` shows which build a run loads.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <torch/csrc/autograd/profiler_legacy.h>
#include <torch/torch.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>

#include <string>
#include <vector>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/layers/layers.h"
#include "nn/models/unet.h"
#include "nn/precision.h"
#include "nn/runtime.h"
#include "nn/tensor_allocator.h"

namespace {

using namespace u3d::nn;

Precision g_precision = Precision::kFp32;
std::string g_profile_path;  // --profile=FILE: a Chrome trace of the ops of every timed forward
bool g_check = false;        // --check: also run the fp32 model and report the relative error against it

struct Case {
  torch::Tensor sample, embedding, timestep, fp32_output;
};

Case make_case(int64_t batch, int64_t size) {
  torch::manual_seed(1);
  return {torch::randn({batch, 4, size, size}), torch::randn({batch, 1, 768}), torch::tensor(500.0f), {}};
}

UNet2DConditionModel build_unet(torch::ScalarType type) {
  auto manifest =
      read_json_file(std::string(UNIQUE3D_SOURCE_DIR) + "/tests/data/nn/manifests/unet_sd_image_variations_plain.json");
  UNet2DConditionModel m(UNetConfig::from_json(manifest.at("constructor_config"), "unet manifest"),
                         torch::TensorOptions().dtype(type));
  torch::manual_seed(0);
  randomize_parameters(*m, 0.02);
  return m;
}

// The model in the chosen precision. Without --check it is built in that precision (so peak RSS is what
// a run in that precision needs); with --check it is built in fp32, run on every case for the
// reference output, then converted.
UNet2DConditionModel& full_size_unet(std::map<int64_t, Case>& cases) {
  static UNet2DConditionModel unet = [&cases] {
    c10::InferenceMode inference;
    if (!g_check) {
      UNet2DConditionModel m = build_unet(scalar_type(g_precision));
      set_precision(*m, g_precision);
      pack_weights_in_place(*m);  // as the pipelines' loaders do: the weights held once
      return m;
    }
    UNet2DConditionModel m = build_unet(torch::kFloat);
    for (auto& [key, c] : cases) c.fp32_output = m->forward(c.sample, c.timestep, c.embedding);
    set_precision(*m, g_precision);
    return m;
  }();
  return unet;
}

std::map<int64_t, Case>& all_cases() {
  static std::map<int64_t, Case> cases{{8 * 1000 + 32, make_case(8, 32)}, {2 * 1000 + 64, make_case(2, 64)}};
  return cases;
}

void BM_UNetForward(benchmark::State& state) {
  c10::InferenceMode inference;
  const int64_t batch = state.range(0), size = state.range(1);
  auto& cases = all_cases();
  UNet2DConditionModel& unet = full_size_unet(cases);
  const Case& c = cases.at(batch * 1000 + size);
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  const TensorAllocatorStats stats_before = tensor_allocator_stats();
  torch::Tensor out;
  for (auto _ : state) {
    std::unique_ptr<torch::autograd::profiler::RecordProfile> profile;
    if (!g_profile_path.empty()) profile = std::make_unique<torch::autograd::profiler::RecordProfile>(g_profile_path);
    out = unet->forward(c.sample, c.timestep, c.embedding);
    benchmark::DoNotOptimize(out.data_ptr());
  }
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  state.counters["threads"] = at::get_num_threads();
  state.SetLabel(precision_name(g_precision));
  // Page faults were a large share of the time (freed tensors handed back to the kernel); peak RSS
  // shows what keeping freed memory costs. new_MB: the tensor allocator's new pages (nn/tensor_allocator.h),
  // the large blocks' share of the faults (4 KiB each).
  state.counters["minor_faults"] = static_cast<double>(after.ru_minflt - before.ru_minflt);
  const TensorAllocatorStats stats_after = tensor_allocator_stats();
  state.counters["mapped_blocks"] = static_cast<double>(stats_after.mapped_blocks - stats_before.mapped_blocks);
  state.counters["new_MB"] = static_cast<double>(stats_after.new_bytes - stats_before.new_bytes) / 1e6;
  state.counters["reused_blocks"] = static_cast<double>(stats_after.reused_blocks - stats_before.reused_blocks);
  state.counters["peak_rss_GB"] = static_cast<double>(after.ru_maxrss) / (1024.0 * 1024.0);
  if (c.fp32_output.defined()) {
    const torch::Tensor ref = c.fp32_output.to(torch::kDouble);
    state.counters["rel_err_vs_fp32"] = ((out.to(torch::kDouble) - ref).norm() / ref.norm()).item<double>();
  }
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
  bool dtype_given = false;
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.starts_with("--dtype=")) {
      try {
        g_precision = parse_precision(arg.substr(8), "--dtype");
      } catch (const u3d::Error& e) {
        std::fprintf(stderr, "bench_unet: %s\n", e.what());
        return 1;
      }
      dtype_given = true;
    } else if (arg == "--check") {
      g_check = true;
    } else if (arg.starts_with("--profile=")) {
      g_profile_path = arg.substr(10);
    } else {
      args.push_back(argv[i]);
    }
  }
  if (!dtype_given) {
    // Both precisions, each in its own process so that its peak RSS is its own (bf16 only where the
    // CPU has the instructions; elsewhere it is emulated and slower than fp32).
    std::string rest;
    for (int i = 1; i < argc; ++i) rest += std::string(" '") + argv[i] + "'";
    int status = 0;
    for (Precision p : {Precision::kFp32, Precision::kBf16}) {
      if (p == Precision::kBf16 && !cpu_has_bf16_kernels()) continue;
      status |= std::system((std::string("'") + argv[0] + "' --dtype=" + precision_name(p) + rest).c_str());
    }
    return status == 0 ? 0 : 1;
  }
  std::string repetitions = "--benchmark_repetitions=3", aggregates = "--benchmark_report_aggregates_only=true";
  args.insert(args.begin() + 1, {repetitions.data(), aggregates.data()});
  int arg_count = static_cast<int>(args.size());
  benchmark::Initialize(&arg_count, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
