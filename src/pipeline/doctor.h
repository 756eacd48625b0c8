#pragma once
// What `unique3d doctor` reports: the machine as the networks see it (CPU, kernels, threads, libtorch,
// device) and the check of every network in a model folder (pipeline/model_check.h), with which commands
// can run on it. In the facade so every front end reports the same.
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/model_check.h"

namespace u3d {

struct SystemReport {
  std::string cpu;               // /proc/cpuinfo's model name
  int cores = 0;                 // hardware threads
  int threads = 0;               // the networks' intra-op threads now in effect
  bool avx512 = false;           // ATen's AVX-512 kernels in use
  bool avx512_bf16 = false;      // native bf16 dot products
  std::string default_precision; // what --dtype auto picks on the CPU
  std::string torch_version;
  bool onednn = false;
  std::string blas;              // libtorch's BLAS, from its build configuration
  std::string cuda;              // "available (N devices)" or why not
};

SystemReport system_report();

struct DoctorReport {
  SystemReport system;
  std::filesystem::path models;
  std::vector<NetworkCheckResult> networks;  // every network, in kAllNetworks order
  bool ok(Network network) const;            // whether `network` passed its check
  // Which runs the folder supports: everything; generate --no-refine; nothing that needs networks.
  bool generate_ready() const;
  bool generate_without_refine_ready() const;
};

// Checks every network of `models` (an Error only when the folder itself does not exist).
DoctorReport run_doctor(const std::filesystem::path& models, NetworkCheck how);

}  // namespace u3d
