// Inside/outside of closed meshes from signed crossings along grid columns: volumes of known solids,
// columns through edges and vertices counted once, crossed (inside-out) plates solid, open meshes
// refused.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "geometry/column_occupancy.h"
#include "test_shapes.h"

namespace u3d {
namespace {

ScalarGrid cube_layout(int n, float lo, float hi) {
  ScalarGrid g;
  g.nx = g.ny = g.nz = n;
  g.origin = Vec3f::Constant(lo);
  g.spacing = (hi - lo) / float(n - 1);
  return g;
}

int inside_count(const ScalarGrid& g) {
  int n = 0;
  for (float v : g.values) n += v > 0.f;
  return n;
}

TEST(ColumnOccupancy, SphereVolume) {
  const float r = 0.6f;
  const Mesh sphere = test::sphere_mesh(r, 4);
  const ScalarGrid g = column_occupancy_field(sphere.positions, sphere.faces, cube_layout(101, -1.f, 1.f));
  const double volume = inside_count(g) * std::pow(double(g.spacing), 3);
  EXPECT_NEAR(volume / (4.0 / 3.0 * M_PI * r * r * r), 0.985, 0.02);  // the icosphere is a little smaller
  // Values are within [-0.5, 0.5] and saturate a voxel away from the surface.
  EXPECT_FLOAT_EQ(g.values[g.index(50, 50, 50)], 0.5f);
  EXPECT_FLOAT_EQ(g.values[g.index(0, 0, 0)], -0.5f);
}

// Box corners and edges exactly on the columns: every column through an edge or a vertex must be
// counted once (an unbalanced count would throw), and the sample count must be exact.
TEST(ColumnOccupancy, GridAlignedBoxIsExact) {
  const ScalarGrid layout = cube_layout(33, -1.f, 1.f);                  // samples every 1/16, exact in float
  const Vec3f lo(-0.5f, -0.3125f, -0.1875f), hi(0.3125f, 0.5f, 0.625f);  // 13 intervals on every axis
  const Mesh box = test::box_mesh(lo, hi);
  const ScalarGrid g = column_occupancy_field(box.positions, box.faces, layout);
  int strictly_inside = 0;
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        const Vec3f p = g.position(x, y, z);
        const float value = g.values[g.index(x, y, z)];
        EXPECT_LE(std::abs(value), 0.5f);
        const Vec3f to_lo = p - lo, to_hi = hi - p;
        if (to_lo.minCoeff() > 0.f && to_hi.minCoeff() > 0.f) {
          EXPECT_GT(value, 0.f) << p.transpose();
          ++strictly_inside;
        }
        if (to_lo.minCoeff() < 0.f || to_hi.minCoeff() < 0.f) {
          EXPECT_LT(value, 0.f) << p.transpose();
        }
        const bool over_face = std::min(to_lo.x(), to_lo.y()) > 0.f && std::min(to_hi.x(), to_hi.y()) > 0.f;
        if (over_face && (to_lo.z() == 0.f || to_hi.z() == 0.f)) {
          EXPECT_EQ(value, 0.f);  // on the top or bottom face
        }
      }
  EXPECT_EQ(strictly_inside, 12 * 12 * 12);
  // Columns on the outline (the side faces) belong to the box on the top-left rule's two sides only:
  // the 13 columns of the edge y = hi.y (with the corner x = lo.x) and the 12 more of x = lo.x, each
  // with the 12 samples strictly between the top and bottom faces. Counted once each: never twice,
  // never open.
  EXPECT_EQ(inside_count(g), 12 * 12 * 12 + (13 + 12) * 12);
}

// The front and back sheets of a plate that crossed during integration: the box turned inside out
// (winding -1 between the sheets) is still solid, with the plate's thickness.
TEST(ColumnOccupancy, CrossedPlateSheetsAreSolid) {
  Mesh plate = test::box_mesh(Vec3f(-0.5f, -0.5f, -0.04f), Vec3f(0.5f, 0.5f, 0.04f));
  for (Vec3i& f : plate.faces) std::swap(f[1], f[2]);  // inside out: front sheet faces back, back faces front
  const ScalarGrid g = column_occupancy_field(plate.positions, plate.faces, cube_layout(101, -1.f, 1.f));
  const double volume = inside_count(g) * std::pow(double(g.spacing), 3);
  EXPECT_NEAR(volume, 1.0 * 1.0 * 0.08, 0.08 * 0.3);
  EXPECT_GT(g.values[g.index(50, 50, 50)], 0.f);
  // Placement along z: the zero crossing between the samples around z = 0.04 lies at 0.04.
  const float below = g.values[g.index(50, 50, 52)], above = g.values[g.index(50, 50, 53)];
  ASSERT_GT(below, 0.f);
  ASSERT_LT(above, 0.f);
  const float z0 = g.position(50, 50, 52).z() + g.spacing * below / (below - above);
  EXPECT_NEAR(z0, 0.04f, 1e-5f);
}

TEST(ColumnOccupancy, OpenMeshIsAnError) {
  Mesh box = test::box_mesh(Vec3f(-0.5f, -0.5f, -0.5f), Vec3f(0.5f, 0.5f, 0.5f));
  box.faces.pop_back();
  box.faces.pop_back();
  bool thrown = false;
  try {
    column_occupancy_field(box.positions, box.faces, cube_layout(11, -1.f, 1.f));
  } catch (const Error& e) {
    thrown = std::string(e.what()).find("not closed") != std::string::npos;
  }
  EXPECT_TRUE(thrown);
}

}  // namespace
}  // namespace u3d
