// One denoising step of each Unique3D model at its official size, full-size random weights, on the CPU
// with every core, run as the pipelines run it:
//  - multi-view (img2mvimg): 4 views at 256 px, the guidance halves one after the other
//    (nn/pipelines/guidance.h), so the UNet sees two batches of 4 at 32x32 latents with joint attention
//    over the 4 views, class labels and the concatenated condition latents;
//  - normal (image2normal): the 4 views at 512 px, per guidance half a reference pass over the 4
//    condition latents and the main UNet, each batch 4 at 64x64 (the unconditional half's condition
//    latents and context are zeros, as the pipeline's);
//  - refine (SD 1.5 + tile ControlNet + IP-Adapter): the 1024 px grid with guidance as one doubled
//    batch, the ControlNet and the UNet each batch 2 at 128x128 latents (16,384 tokens in the first
//    level's self-attention), the UNet's context 77 text + 4 image tokens.
// Prints seconds per step (median of --repetitions, default 3), the resident memory before the first
// step (the weights) and the peak RSS (of the whole process: run one step kind with --only to see its
// own; GB here are GiB). A full run is 30 steps each for the first two, 10 for refine.
// --memory-profile adds the peak of the tensor memory the steps allocate beyond the weights, with the
// ATen ops open when it is reached (libtorch's memory reports and op callbacks; it slows the steps).
// --save=FILE writes each step's prediction (named multiview, normal, refine) to a safetensors file,
// to compare two builds' outputs bit for bit (the weights and inputs come from a fixed seed).
// Usage: bench_unique3d_steps [--dtype=fp32|bf16] [--repetitions=N] [--only=multiview|normal|refine]
//                             [--memory-profile] [--save=FILE]
#include <sys/resource.h>
#include <unistd.h>
#include <ATen/record_function.h>
#include <c10/core/Allocator.h>
#include <c10/util/ThreadLocalDebugInfo.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/layers/layers.h"
#include "nn/layers/multiview_attention.h"
#include "nn/models/controlnet.h"
#include "nn/models/ip_adapter.h"
#include "nn/models/unet.h"
#include "nn/models/unet_reference.h"
#include "nn/pipelines/guidance.h"
#include "nn/precision.h"
#include "nn/runtime.h"
#include "nn/tensor_allocator.h"

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

// The resident memory now (the weights, before a step), from /proc/self/statm; 0 where it is not readable.
double resident_gb() {
  long pages_total = 0, pages_resident = 0;
  if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages_total, &pages_resident) != 2) pages_resident = 0;
    std::fclose(f);
  }
  return static_cast<double>(pages_resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0 * 1024.0);
}

double peak_rss_gb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0);
}


// --memory-profile: the peak of the tensor memory a step allocates beyond what exists before it
// (libtorch reports every CPU allocation and free to the profiler's debug-info slot), and the ATen ops
// open on the main thread when it is reached.
class MemoryPeakTracker : public c10::MemoryReportingInfoBase {
 public:
  void reportMemoryUsage(void*, int64_t bytes, int64_t, int64_t, c10::Device) override {
    std::lock_guard<std::mutex> lock(mutex_);
    live_ += bytes;
    if (live_ > peak_) {
      peak_ = live_;
      peak_ops_ = ops_;
    }
  }
  bool memoryProfilingEnabled() const override { return true; }
  void push(std::string op) {
    std::lock_guard<std::mutex> lock(mutex_);
    ops_.push_back(std::move(op));
  }
  void pop() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!ops_.empty()) ops_.pop_back();
  }
  void print() const {
    std::printf("tensor memory the step allocates: peak %.1f MiB, %.1f MiB still held at the end; open ops at the peak:\n",
                peak_ / 1048576.0, live_ / 1048576.0);
    for (const std::string& op : peak_ops_) std::printf("  %s\n", op.c_str());
  }

 private:
  std::mutex mutex_;
  int64_t live_ = 0, peak_ = 0;
  std::vector<std::string> ops_, peak_ops_;
};

MemoryPeakTracker* g_tracker = nullptr;

std::unique_ptr<at::ObserverContext> on_op_start(const at::RecordFunction& fn) {
  std::string op = fn.name();
  for (const c10::IValue& input : fn.inputs())
    if (input.isTensor() && input.toTensor().defined()) op += " " + c10::str(input.toTensor().sizes());
  g_tracker->push(std::move(op));
  return nullptr;
}

void on_op_end(const at::RecordFunction&, at::ObserverContext*) { g_tracker->pop(); }

// median_seconds, with --memory-profile's report of the steps' tensor memory after it.
double timed_steps(int repetitions, bool memory_profile, const std::function<void()>& step) {
  if (!memory_profile) return median_seconds(repetitions, step);
  auto tracker = std::make_shared<MemoryPeakTracker>();
  g_tracker = tracker.get();
  const at::CallbackHandle callbacks =
      at::addThreadLocalCallback(at::RecordFunctionCallback(on_op_start, on_op_end).needsInputs(true));
  double seconds = 0;
  {
    c10::DebugInfoGuard tracking(c10::DebugInfoKind::PROFILER_STATE, tracker);
    seconds = median_seconds(repetitions, step);
  }
  at::removeCallback(callbacks);
  tracker->print();
  g_tracker = nullptr;
  return seconds;
}

// The large tensor blocks (nn/tensor_allocator.h) mapped anew and reused from the cache so far.
void print_allocator_stats() {
  const TensorAllocatorStats s = tensor_allocator_stats();
  std::printf("  large tensor blocks so far: %zu mapped, %zu reused from the cache\n", s.mapped_blocks, s.reused_blocks);
}

}  // namespace

int main(int argc, char** argv) try {
  Precision precision = Precision::kFp32;
  int repetitions = 3;
  std::string only;
  bool memory_profile = false;
  std::string save;
  const std::string usage =
      "usage: bench_unique3d_steps [--dtype=fp32|bf16] [--repetitions=N] [--only=multiview|normal|refine] "
      "[--memory-profile] [--save=FILE]";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.starts_with("--dtype="))
      precision = parse_precision(arg.substr(8), "--dtype");
    else if (arg.starts_with("--repetitions="))
      repetitions = std::max(1, std::stoi(arg.substr(14)));
    else if (arg == "--memory-profile")
      memory_profile = true;
    else if (arg.starts_with("--save="))
      save = arg.substr(7);
    else if (arg == "--only=multiview" || arg == "--only=normal" || arg == "--only=refine")
      only = arg.substr(7);
    else
      throw u3d::Error("unknown argument '" + arg + "' (" + usage + ")");
  }
  auto wanted = [&](const std::string& name) { return only.empty() || only == name; };
  configure_torch_threads();
  at::globalContext().setFlushDenormal(true);  // random weights: keep the FPU off its denormal path
  c10::InferenceMode inference;
  const auto options = torch::TensorOptions().dtype(scalar_type(precision));
  torch::manual_seed(0);
  TensorMap predictions;  // --save

  if (wanted("multiview")) {
    UNet2DConditionModel unet(manifest_config("unet_unique3d_img2mvimg"), options);
    randomize_parameters(*unet, 0.02);
    set_precision(*unet, precision);
    pack_weights_in_place(*unet);  // as the pipeline's loaders
    set_attention_processors(*unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(4)));
    torch::Tensor x = torch::randn({4, 4, 32, 32}), context = torch::randn({8, 1, 768});
    torch::Tensor condition = torch::randn({2, 4, 32, 32});
    const double before = resident_gb();
    const double s = timed_steps(repetitions, memory_profile, [&] {
      predictions["multiview"] = guided_prediction(1.5, [&](GuidanceHalf half) {
        UNetExtras extras;
        extras.class_labels = torch::arange(4, torch::kLong);
        extras.condition_latents = batch_half(condition, half);
        return unet->forward(x, torch::tensor(500.0f), batch_half(context, half), extras);
      }).combined;
    });
    std::printf("multi-view step (two halves of batch 4 at 32x32, 4 joint views)  %s: %6.2f s   resident before %.2f GB, peak RSS %.2f GB\n",
                precision_name(precision), s, before, peak_rss_gb());
    print_allocator_stats();
  }
  if (wanted("normal")) {
    ReferenceUNet model(manifest_config("unet_unique3d_image2normal"), options);
    randomize_parameters(*model.unet, 0.02);  // the reference UNet is registered inside it
    set_precision(*model.unet, precision);
    pack_weights_in_place(*model.unet);
    // As the pipeline: the unconditional half's context and condition latents are zeros.
    torch::Tensor x = torch::randn({4, 4, 64, 64});
    torch::Tensor context = torch::cat({torch::zeros({4, 1, 768}), torch::randn({4, 1, 768})});
    torch::Tensor condition = torch::cat({torch::zeros({4, 4, 64, 64}), torch::randn({4, 4, 64, 64})});
    const double before = resident_gb();
    const double s = timed_steps(repetitions, memory_profile, [&] {
      predictions["normal"] = guided_prediction(1.5, [&](GuidanceHalf half) {
        return model.forward(x, torch::tensor(500.0f), batch_half(context, half), batch_half(condition, half));
      }).combined;
    });
    std::printf("normal step (4 views: reference + main, two halves of batch 4 at 64x64) %s: %6.2f s (%.2f s a view)"
                "   resident before %.2f GB, peak RSS %.2f GB\n",
                precision_name(precision), s, s / 4, before, peak_rss_gb());
    print_allocator_stats();
  }
  if (wanted("refine")) {
    // SD 1.5's UNet has the sd-image-variations architecture (cross-attention dim 768).
    UNet2DConditionModel unet(manifest_config("unet_sd_image_variations_plain"), options);
    IpAdapter adapter(*unet, 1024, 4, 1.0, options);
    auto controlnet_manifest = read_json_file(std::string(UNIQUE3D_SOURCE_DIR) + "/tests/data/nn/manifests/controlnet_sd15.json");
    ControlNetModel controlnet(ControlNetConfig::from_json(controlnet_manifest.at("constructor_config"), "controlnet_sd15"),
                               options);
    for (torch::nn::Module* m : {static_cast<torch::nn::Module*>(unet.get()), static_cast<torch::nn::Module*>(adapter.get()),
                                 static_cast<torch::nn::Module*>(controlnet.get())}) {
      randomize_parameters(*m, 0.02);
      set_precision(*m, precision);
      pack_weights_in_place(*m);
    }
    torch::Tensor x = torch::randn({2, 4, 128, 128}), text = torch::randn({2, 77, 768});
    torch::Tensor context = adapter->context(text, torch::randn({2, 1024}));
    // The pipeline embeds its control image (both halves) once a run (ControlNetModel::embed_condition).
    const torch::Tensor control_image = torch::rand({1, 3, 1024, 1024});
    const torch::Tensor control = controlnet->embed_condition(torch::cat({control_image, control_image}));
    const double before = resident_gb();
    const double s = timed_steps(repetitions, memory_profile, [&] {
      ControlNetOutput residuals = controlnet->forward_embedded(x, torch::tensor(500.0f), text, control);
      UNetExtras extras;
      extras.down_block_additional_residuals = std::move(residuals.down_block_res_samples);
      extras.mid_block_additional_residual = std::move(residuals.mid_block_res_sample);
      predictions["refine"] = unet->forward(x, torch::tensor(500.0f), context, std::move(extras));
    });
    std::printf("refine step (ControlNet + UNet with IP-Adapter, batch 2 at 128x128) %s: %6.2f s   resident before %.2f GB, peak RSS %.2f GB\n",
                precision_name(precision), s, before, peak_rss_gb());
    print_allocator_stats();
  }
  if (!save.empty()) save_safetensors(predictions, save);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_unique3d_steps: %s\n", e.what());
  return 1;
}
