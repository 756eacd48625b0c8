#include "nn/runtime.h"

#include <ATen/Parallel.h>
#include <gtest/gtest.h>

TEST(Runtime, ConfiguresTorchThreads) {
  EXPECT_EQ(u3d::nn::configure_torch_threads(2), 2);
  EXPECT_EQ(at::get_num_threads(), 2);
  EXPECT_EQ(u3d::nn::configure_torch_threads(1), 1);
  EXPECT_GE(u3d::nn::configure_torch_threads(0), 1);
}
