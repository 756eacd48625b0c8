#include "pipeline/network_stage.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>

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

namespace {

// The resident set now in MiB (/proc/self/statm), 0 where it is not readable.
double resident_mib() {
  std::ifstream statm("/proc/self/statm");
  long total = 0, resident = 0;
  if (!(statm >> total >> resident)) return 0.0;
  return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

}  // namespace

struct MemoryPeakWatch::Sampler {
  std::mutex mutex;
  std::condition_variable wake;
  bool stop = false;
  double peak_mib = 0.0;
  std::thread thread;

  Sampler() : peak_mib(resident_mib()) {
    thread = std::thread([this] {
      std::unique_lock<std::mutex> lock(mutex);
      while (!stop) {
        peak_mib = std::max(peak_mib, resident_mib());
        wake.wait_for(lock, std::chrono::milliseconds(kSampleMilliseconds));
      }
    });
  }
  double finish() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    wake.notify_all();
    if (thread.joinable()) thread.join();
    return std::max(peak_mib, resident_mib());
  }
  ~Sampler() { finish(); }
};

MemoryPeakWatch::MemoryPeakWatch() : sampler_(std::make_unique<Sampler>()), start_hwm_mib_(peak_memory_mib()) {}

MemoryPeakWatch::~MemoryPeakWatch() = default;

double MemoryPeakWatch::peak_mib() {
  const double sampled = sampler_->finish();
  const double hwm = peak_memory_mib();
  return hwm > start_hwm_mib_ ? hwm : sampled;
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
