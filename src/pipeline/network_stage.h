#pragma once
// What the facade's network stages share: the model folder, precision and seed a request carries, the
// summary a stage hands back, and the conversions between the command's images (core/image.h) and the
// 8-bit tensors the networks' preprocessing takes (the official code works on 8-bit PIL images).
#include <cstdint>
#include <filesystem>
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

// The process's peak resident memory in MiB since it started or since the last reset_peak_memory()
// (the kernel's VmHWM; getrusage where /proc is not readable).
double peak_memory_mib();

// Starts a new peak from the current resident memory (Linux's /proc/self/clear_refs), so that a run of
// stages can report each stage's own peak; where the kernel does not allow it the peak keeps counting
// from the start of the process.
void reset_peak_memory();

// PIL's rgba_to_rgb of the official app: the image composited over white (Pillow's paste with its own
// alpha as the mask, 8-bit arithmetic), as RGB. RGB images pass through.
Image composite_over_white(const Image& rgba);

}  // namespace u3d
