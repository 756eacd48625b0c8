#include "nn/runtime.h"

#include <ATen/Parallel.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdlib>
#include <cstring>
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

namespace {

long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// Allocates and touches `bytes`, frees them; returns the page faults this took.
long faults_to_fill_a_fresh_block(size_t bytes) {
  const long before = minor_faults();
  void* block = std::malloc(bytes);
  std::memset(block, 1, bytes);
  asm volatile("" : : "r"(block) : "memory");  // the compiler may not drop the unused block
  std::free(block);
  return minor_faults() - before;
}

}  // namespace

TEST(Runtime, FreedLargeBlocksAreReusedWithoutPageFaults) {
  u3d::nn::keep_freed_memory_for_reuse();
  const size_t bytes = size_t{64} << 20;  // above glibc's largest mmap threshold (32 MB)
  faults_to_fill_a_fresh_block(bytes);    // maps the pages once
  const long pages = static_cast<long>(bytes / 4096);
  // Without the set-up every one of the 16384 pages faults again.
  EXPECT_LT(faults_to_fill_a_fresh_block(bytes), pages / 10);
}
