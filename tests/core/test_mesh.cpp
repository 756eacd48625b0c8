// Normalising a mesh into the unit box: the messages for meshes that cannot be.
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "core/mesh.h"

using namespace u3d;

namespace {

Mesh triangle(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  Mesh m;
  m.positions = {a, b, c};
  m.faces = {Vec3i(0, 1, 2)};
  return m;
}

std::string normalize_error(Mesh mesh) {
  try {
    normalize_to_unit_box(mesh, 0.9f);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Mesh, NormalizeFitsTheLongestSideToTheFill) {
  Mesh m = triangle({1, 1, 1}, {5, 1, 1}, {1, 3, 1});
  normalize_to_unit_box(m, 0.9f);
  EXPECT_NEAR(m.positions[0].x(), -0.9f, 1e-6f);
  EXPECT_NEAR(m.positions[1].x(), 0.9f, 1e-6f);
  EXPECT_NEAR(m.positions[2].y(), 0.45f, 1e-6f);
}

TEST(Mesh, NormalizeTellsAPointFromAMeshBeyondTheFloatRange) {
  EXPECT_NE(normalize_error(triangle({1, 2, 3}, {1, 2, 3}, {1, 2, 3})).find("zero size"), std::string::npos);
  // The extent of these overflows a float: this mesh is huge, not flat.
  const std::string huge = normalize_error(triangle({-3e38f, 0, 0}, {3e38f, 0, 0}, {0, 3e38f, 0}));
  EXPECT_NE(huge.find("beyond 1e30"), std::string::npos) << huge;
  // Small but far away: the centre would overflow.
  const std::string far = normalize_error(triangle({3e38f, 0, 0}, {3e38f, 1e32f, 0}, {3e38f, 0, 1e32f}));
  EXPECT_NE(far.find("beyond 1e30"), std::string::npos) << far;
}
