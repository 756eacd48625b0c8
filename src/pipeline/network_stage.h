#pragma once
// What the facade's network stages share: the model folder, precision and seed a request carries, the
// summary a stage hands back, and the conversions between the command's images (core/image.h) and the
// 8-bit tensors the networks' preprocessing takes (the official code works on 8-bit PIL images).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "isomer/stage_report.h"
#include "nn/precision_kind.h"

namespace u3d {

// The official app's default seed (run_mvprediction).
inline constexpr uint64_t kDefaultSeed = 1145;

struct NetworkOptions {
  std::filesystem::path models;            // --models (pipeline/model_folder.h)
  std::optional<nn::Precision> precision;  // unset: the device's default (nn/precision.h)
  uint64_t seed = kDefaultSeed;            // every stage draws its noise from this seed
};

struct NetworkStageSummary {
  nn::Precision precision = nn::Precision::kFp32;  // what the networks ran in
  std::vector<StageTiming> timings;
  std::vector<std::filesystem::path> written;
  double peak_memory_mib = 0.0;  // the process's peak resident memory so far
  double total_seconds() const;
};

// The precision the request asks for, or the CPU's default; an Error when it cannot run here, a warning
// (once) when it runs slowly here: bf16 without avx512_bf16.
nn::Precision resolve_precision(const NetworkOptions& options);

// The process's peak resident memory in MiB since it started (the kernel's VmHWM, which is what
// getrusage's ru_maxrss and `/usr/bin/time -v` report; getrusage where /proc is not readable).
double peak_memory_mib();

// The peak resident memory of one part of a run (a stage of `generate`), from construction to
// peak_mib(). It leaves the kernel's record of the process's peak alone: resetting it
// (/proc/self/clear_refs) would also reset what getrusage and `/usr/bin/time -v` report for the whole
// process, which then gave only the last stage's peak. Exact when the part raised the process's peak
// (VmHWM grew: the part's peak is the new VmHWM); otherwise the highest resident size a thread samples
// every kSampleMilliseconds (/proc/self/statm), which can miss a peak shorter than that.
class MemoryPeakWatch {
 public:
  static constexpr int kSampleMilliseconds = 5;
  MemoryPeakWatch();
  ~MemoryPeakWatch();
  MemoryPeakWatch(const MemoryPeakWatch&) = delete;
  MemoryPeakWatch& operator=(const MemoryPeakWatch&) = delete;
  double peak_mib();  // stops the sampling

 private:
  struct Sampler;
  std::unique_ptr<Sampler> sampler_;
  double start_hwm_mib_ = 0.0;
};

// PIL's rgba_to_rgb of the official app: the image composited over white (Pillow's paste with its own
// alpha as the mask, 8-bit arithmetic), as RGB. RGB images pass through.
Image composite_over_white(const Image& rgba);

}  // namespace u3d
