// solid_matte on drawn masks whose right answer is known: a ring keeps its hole, a faded body inside a
// confident rim becomes opaque, soft edges and whatever reaches the border keep the network's alpha.
// (The measure on a real photo is tests/nn/test_matting.cpp, Matting.RealIsNetMakesTheBagSolid.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/error.h"
#include "core/solid_matte.h"

namespace u3d {
namespace {

constexpr int kSize = 256;  // edge radius: 1 px

// An alpha image whose value at (x, y) is f(distance from the centre).
Image radial(const std::function<float(double)>& f, int size = kSize) {
  Image alpha(size, size, 1);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) alpha.at(x, y, 0) = f(std::hypot(x + 0.5 - size / 2.0, y + 0.5 - size / 2.0));
  return alpha;
}

// A linear edge from 1 (inside r) to 0 (outside r + width).
float ramp_down(double d, double r, double width) { return float(std::clamp((r + width - d) / width, 0.0, 1.0)); }

TEST(SolidMatte, RingKeepsItsHole) {
  // A ring between radii 40 and 90 with 4 px soft edges on both sides, clear inside and outside. Its
  // hole is a region below the core that the ring encloses, and stays open because it is clear.
  const Image ring = radial([](double d) {
    return std::min(ramp_down(d, 90, 4), ramp_down(-d, -40, 4));  // inner edge: 0 below 36, 1 beyond 40
  });
  const Image solid = solid_matte(ring);
  for (size_t i = 0; i < ring.data.size(); ++i) {
    EXPECT_GE(solid.data[i], ring.data[i]) << i;
    if (ring.data[i] <= kSolidMatteClear) {
      EXPECT_EQ(solid.data[i], ring.data[i]) << i;  // the hole, the outside
    }
  }
  // The ring itself is opaque.
  EXPECT_EQ(solid.at(kSize / 2 + 60, kSize / 2, 0), 1.f);
}

TEST(SolidMatte, FadedBodyInsideAConfidentRimBecomesOpaque) {
  // A disk of radius 100: a 6 px rim at 0.95, inside it a body at 0.3 with a patch at 0.6; a 3 px
  // soft outer edge.
  const Image body = radial([](double d) {
    if (d > 100) return ramp_down(d, 100, 3) * 0.95f;
    if (d > 94) return 0.95f;
    return d < 30 ? 0.6f : 0.3f;
  });
  const Image solid = solid_matte(body);
  int opaque = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double d = std::hypot(x + 0.5 - kSize / 2.0, y + 0.5 - kSize / 2.0);
      const float before = body.at(x, y, 0), after = solid.at(x, y, 0);
      if (before < kSolidMatteCore && d > 100) {
        EXPECT_EQ(after, before) << x << ", " << y;  // the outside, its soft edge included
      } else if (d < 98) {
        EXPECT_EQ(after, 1.f) << x << ", " << y;  // the body and the rim, beyond the edge radius
        ++opaque;
      }
    }
  EXPECT_GT(opaque, 3.14 * 97 * 97 * 0.99);
}

TEST(SolidMatte, SoftEdgesKeepTheNetworksAlphaWithinTheEdgeRadius) {
  // A disk with a 20 px linear edge, on a 1024 px image: edge radius 4 px. Below the core threshold the
  // edge reaches the border and is kept; above it, the first 4 px are kept and beyond 8 px all is opaque.
  const int size = 1024;
  const Image soft = radial([](double d) { return ramp_down(d, 200, 20); }, size);
  const Image solid = solid_matte(soft);
  const double half = 210.0;  // where the ramp crosses 0.5
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double d = std::hypot(x + 0.5 - size / 2.0, y + 0.5 - size / 2.0);
      const float before = soft.at(x, y, 0), after = solid.at(x, y, 0);
      if (before < kSolidMatteCore || d > half - 3) {
        EXPECT_EQ(after, before) << x << ", " << y;
      }
      if (d < half - 8.5) {
        EXPECT_EQ(after, 1.f) << x << ", " << y;
      }
    }
}

TEST(SolidMatte, HolesStayOpenSpecksCloseAndWhatReachesTheBorderIsKept) {
  // A square subject at 0.4 inside a rim at 1: a clear 20 px hole in it (1.6 % of the subject: a hole), a
  // clear speck (a patch the network missed: closed), and a band at 0.3 (a shadow) from the subject to the
  // image's right border.
  Image alpha(kSize, kSize, 1, 0.f);
  for (int y = 40; y < 200; ++y)
    for (int x = 40; x < 200; ++x) {
      const bool rim = x < 46 || x >= 194 || y < 46 || y >= 194;
      alpha.at(x, y, 0) = rim ? 1.f : 0.4f;
    }
  for (int y = 100; y < 120; ++y)
    for (int x = 100; x < 120; ++x) alpha.at(x, y, 0) = 0.05f;  // the hole
  for (int y = 60; y < 64; ++y)
    for (int x = 150; x < 154; ++x) alpha.at(x, y, 0) = 0.f;  // a clear speck of 16 px, < 1 % of the subject
  for (int y = 210; y < 230; ++y)
    for (int x = 60; x < kSize; ++x) alpha.at(x, y, 0) = 0.3f;  // the shadow, apart from the subject
  const Image solid = solid_matte(alpha);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const float before = alpha.at(x, y, 0), after = solid.at(x, y, 0);
      const bool near_hole = x >= 99 && x < 121 && y >= 99 && y < 121;  // the hole and 1 px (< 2 edge radii)
      const bool inside = x >= 41 && x < 199 && y >= 41 && y < 199;     // the subject less 1 px
      if (inside && !near_hole) {
        EXPECT_EQ(after, 1.f) << x << ", " << y;
      } else if (!inside || (x >= 100 && x < 120 && y >= 100 && y < 120)) {
        EXPECT_EQ(after, before) << x << ", " << y;
      }
    }
}

TEST(SolidMatte, RejectsImagesThatAreNotAnAlpha) {
  EXPECT_THROW(solid_matte(Image(8, 8, 3, 0.5f)), Error);
  EXPECT_THROW(solid_matte(Image()), Error);
}

}  // namespace
}  // namespace u3d
