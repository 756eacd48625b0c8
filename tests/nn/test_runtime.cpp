#include "nn/runtime.h"

#include <ATen/Parallel.h>
#include <gtest/gtest.h>

#include <cstdlib>
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
