#include "pipeline/doctor.h"

#include <ATen/Version.h>
#include <torch/torch.h>
#include <torch/version.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <thread>

#include "nn/precision.h"
#include "nn/runtime.h"

namespace u3d {
namespace {

std::string cpu_model_name() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos) {
      std::string name = line.substr(line.find(':') + 1);
      name.erase(0, name.find_first_not_of(' '));
      return name;
    }
  return "unknown";
}

// The BLAS line of libtorch's build configuration ("BLAS_INFO=open" for OpenBLAS).
std::string blas_name() {
  std::istringstream config(at::show_config());
  for (std::string line; std::getline(config, line);) {
    const size_t at = line.find("BLAS_INFO=");
    if (at != std::string::npos) {
      std::string value = line.substr(at + 10);
      value = value.substr(0, value.find_first_of(", "));
      return value == "open" ? "OpenBLAS" : value;
    }
  }
  return "unknown";
}

}  // namespace

SystemReport system_report() {
  SystemReport s;
  s.cpu = cpu_model_name();
  s.cores = int(std::max(1u, std::thread::hardware_concurrency()));
  s.threads = int(at::get_num_threads());
  s.avx512 = nn::cpu_runs_avx512_kernels();
  s.avx512_bf16 = nn::cpu_has_bf16_kernels();
  s.default_precision = nn::precision_name(nn::default_precision(torch::kCPU));
  s.torch_version = TORCH_VERSION;
  s.onednn = at::hasMKLDNN();
  s.blas = blas_name();
  s.cuda = torch::cuda::is_available()
               ? "available (" + std::to_string(torch::cuda::device_count()) + " devices)"
               : "not available (this libtorch build has no CUDA, or there is no GPU): the networks run on the CPU";
  return s;
}

bool DoctorReport::ok(Network network) const {
  for (const NetworkCheckResult& r : networks)
    if (r.network == network) return r.ok();
  return false;
}

bool DoctorReport::generate_without_refine_ready() const {
  return ok(Network::kUpscaler) && ok(Network::kMultiView) && ok(Network::kNormals);
}

bool DoctorReport::generate_ready() const { return generate_without_refine_ready() && ok(Network::kRefine); }

DoctorReport run_doctor(const std::filesystem::path& models, NetworkCheck how) {
  DoctorReport report;
  report.system = system_report();
  report.models = models;
  const ModelFolder folder(models);
  for (Network network : kAllNetworks) report.networks.push_back(check_network(folder, network, how));
  return report;
}

}  // namespace u3d
