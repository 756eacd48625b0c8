#include "nn/runtime.h"

#include <ATen/Parallel.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

TEST(Runtime, ConfiguresTorchThreads) {
  EXPECT_EQ(u3d::nn::configure_torch_threads(2), 2);
  EXPECT_EQ(at::get_num_threads(), 2);
  EXPECT_EQ(u3d::nn::configure_torch_threads(1), 1);
  EXPECT_GE(u3d::nn::configure_torch_threads(0), 1);
}

TEST(Runtime, AsksForAvx512KernelsUnlessTheUserChose) {
  const char* before = std::getenv("ATEN_CPU_CAPABILITY");
  const std::string saved = before ? before : "";
  unsetenv("ATEN_CPU_CAPABILITY");
  u3d::nn::configure_torch_threads(1);
  if (u3d::nn::cpu_runs_avx512_kernels()) {
    ASSERT_NE(std::getenv("ATEN_CPU_CAPABILITY"), nullptr);
    EXPECT_EQ(std::string(std::getenv("ATEN_CPU_CAPABILITY")), "avx512");
  } else {
    EXPECT_EQ(std::getenv("ATEN_CPU_CAPABILITY"), nullptr);  // never ask for kernels the CPU cannot run
  }
  setenv("ATEN_CPU_CAPABILITY", "default", 1);  // a user's choice is kept
  u3d::nn::configure_torch_threads(1);
  EXPECT_EQ(std::string(std::getenv("ATEN_CPU_CAPABILITY")), "default");
  if (before) setenv("ATEN_CPU_CAPABILITY", saved.c_str(), 1); else unsetenv("ATEN_CPU_CAPABILITY");
}

// CMakeLists.txt links the programs so that libtorch loads the OpenMP build of OpenBLAS wherever it is
// installed, whichever build the system's alternatives select.
TEST(Runtime, LoadsTheOpenMpBuildOfOpenBlasWhereInstalled) {
  std::ifstream maps("/proc/self/maps");
  ASSERT_TRUE(maps.good());
  std::set<std::string> openblas;
  for (std::string line; std::getline(maps, line);) {
    const auto slash = line.find('/');
    if (slash != std::string::npos && line.find("openblas", slash) != std::string::npos) openblas.insert(line.substr(slash));
  }
  if (openblas.empty()) GTEST_SKIP() << "this libtorch does not use OpenBLAS";
  const std::string pthread_dir = "/openblas-pthread/", openmp_dir = "/openblas-openmp/";
  for (const std::string& path : openblas) {
    const auto at = path.find(pthread_dir);
    if (at == std::string::npos) continue;
    std::string openmp_build = path;
    openmp_build.replace(at, pthread_dir.size(), openmp_dir);
    EXPECT_FALSE(std::filesystem::exists(openmp_build)) << path << " is loaded although " << openmp_build << " is installed";
  }
}
