#include <gtest/gtest.h>

#include "core/color_space.h"

using namespace u3d;

TEST(ColorSpace, EndpointsAndKnownValues) {
  EXPECT_EQ(srgb_to_linear(0.f), 0.f);
  EXPECT_EQ(srgb_to_linear(1.f), 1.f);
  EXPECT_EQ(linear_to_srgb(0.f), 0.f);
  EXPECT_EQ(linear_to_srgb(1.f), 1.f);
  EXPECT_NEAR(srgb_to_linear(0.5f), 0.2140411f, 1e-6f);   // not 0.5^2.2 = 0.2176
  EXPECT_NEAR(srgb_to_linear(0.04f), 0.04f / 12.92f, 1e-9f);  // linear toe
  EXPECT_NEAR(linear_to_srgb(0.2140411f), 0.5f, 1e-6f);
}

TEST(ColorSpace, RoundTripIsNearlyExact) {
  for (int i = 0; i <= 1000; ++i) {
    float c = i / 1000.f;
    EXPECT_NEAR(linear_to_srgb(srgb_to_linear(c)), c, 1e-6f) << c;
  }
}
