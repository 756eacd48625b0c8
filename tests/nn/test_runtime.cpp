#include "nn/runtime.h"

#include <ATen/Parallel.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

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

// Runs only inside the restarted child of the next test (the marker variable is set there).
TEST(Runtime, RestartedProgramSeesPassiveWaitPolicy) {
  if (std::getenv("U3D_TEST_RESTART_CHILD") == nullptr) GTEST_SKIP() << "only meaningful in the restarted child";
  ASSERT_NE(std::getenv("OMP_WAIT_POLICY"), nullptr);
  EXPECT_EQ(std::string(std::getenv("OMP_WAIT_POLICY")), "PASSIVE");
}

TEST(Runtime, RestartsWithPassiveOpenMpWaitsUnlessTheUserChose) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    unsetenv("OMP_WAIT_POLICY");
    unsetenv("GOMP_SPINCOUNT");
    setenv("U3D_TEST_RESTART_CHILD", "1", 1);
    std::string program = "test_nn", filter = "--gtest_filter=Runtime.RestartedProgramSeesPassiveWaitPolicy";
    char* argv[] = {program.data(), filter.data(), nullptr};
    u3d::nn::restart_with_passive_openmp_waits(argv);
    _exit(77);  // not restarted
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);  // the restarted test passed (77: no restart, 1: wrong policy)

  // A choice already in the environment means no restart: the call returns.
  setenv("GOMP_SPINCOUNT", "1000", 1);
  u3d::nn::restart_with_passive_openmp_waits(nullptr);
  unsetenv("GOMP_SPINCOUNT");
}
