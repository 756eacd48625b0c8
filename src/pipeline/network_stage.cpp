#include "pipeline/network_stage.h"

#include <sys/resource.h>

#include <cmath>
#include <fstream>
#include <mutex>
#include <string>

#include "core/progress.h"
#include "nn/precision.h"

namespace u3d {

double NetworkStageSummary::total_seconds() const {
  double total = 0.0;
  for (const StageTiming& t : timings) total += t.seconds;
  return total;
}

nn::Precision resolve_precision(const NetworkOptions& options) {
  const torch::Device cpu(torch::kCPU);
  const nn::Precision precision = options.precision.value_or(nn::default_precision(cpu));
  nn::check_precision_supported(precision, cpu);
  if (precision == nn::Precision::kBf16 && !nn::cpu_has_bf16_kernels()) {
    static std::once_flag warned;
    std::call_once(warned, [] {
      progress(
          "warning: this CPU lacks avx512_bf16, so bf16 runs without native kernels, over 70 times slower "
          "than fp32 (one UNet forward at 512 px: over 20 min against 17 s); --dtype fp32, the default here, "
          "is the fast choice");
    });
  }
  return precision;
}

double peak_memory_mib() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // "VmHWM:  123 kB"
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

void reset_peak_memory() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";  // resets the peak resident set size (Linux >= 4.0); a failure leaves the old peak
}

Image composite_over_white(const Image& rgba) {
  if (rgba.channels != 4) return rgba;
  Image rgb(rgba.width, rgba.height, 3);
  for (size_t i = 0; i < rgba.pixel_count(); ++i) {
    const float* p = rgba.data.data() + 4 * i;
    const int a = int(std::lround(p[3] * 255.f));
    for (int c = 0; c < 3; ++c) {
      // Pillow's paste: (src * a + dst * (255 - a)) / 255 rounded with its DIV255, over dst = 255.
      const int v = int(std::lround(p[c] * 255.f)) * a + 255 * (255 - a) + 128;
      rgb.data[3 * i + c] = float(((v >> 8) + v) >> 8) / 255.f;
    }
  }
  return rgb;
}

}  // namespace u3d
