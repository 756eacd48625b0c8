// A closed mesh's signed distance on a grid: the exact distance to a box near its surface, with the
// sign of the inside, clamped beyond the band; and a grid surface of it lies on the mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "geometry/marching_tetrahedra.h"
#include "geometry/mesh_topology.h"
#include "geometry/signed_distance.h"
#include "test_shapes.h"

namespace u3d {
namespace {

using test::box_mesh;

ScalarGrid empty_grid(int n, float spacing) {
  ScalarGrid grid;
  grid.nx = grid.ny = grid.nz = n;
  grid.origin = Vec3f::Constant(-0.5f * spacing * float(n - 1));
  grid.spacing = spacing;
  return grid;
}

// The signed distance to an axis-aligned box, positive inside.
float box_distance(const Vec3f& p, const Vec3f& lo, const Vec3f& hi) {
  const Vec3f centre = 0.5f * (lo + hi), half = 0.5f * (hi - lo);
  const Vec3f q = (p - centre).cwiseAbs() - half;  // > 0 on the axes where p lies outside the slab
  const float outside = q.cwiseMax(0.f).norm();
  return outside > 0.f ? -outside : -q.maxCoeff();
}

// Off the sample positions: no sample lies on a face.
const Vec3f kLo(-0.43f, -0.37f, -0.29f), kHi(0.41f, 0.33f, 0.47f);

TEST(SignedDistance, BoxIsExactWithinTheBandAndClampedBeyond) {
  ScalarGrid grid = empty_grid(41, 0.05f);
  const float band = 0.12f;
  sample_signed_distance(box_mesh(kLo, kHi), band, grid);
  ASSERT_EQ(grid.values.size(), size_t(41 * 41 * 41));
  int inside = 0;
  for (int z = 0; z < grid.nz; ++z)
    for (int y = 0; y < grid.ny; ++y)
      for (int x = 0; x < grid.nx; ++x) {
        const float expected = std::clamp(box_distance(grid.position(x, y, z), kLo, kHi), -band, band);
        ASSERT_NEAR(grid.values[grid.index(x, y, z)], expected, 1e-5f) << x << " " << y << " " << z;
        inside += expected > 0.f;
      }
  EXPECT_GT(inside, 1000);
}

// A sphere's grid surface from its mesh's signed distance lies on the sphere: the parity of the column
// crossings holds where columns pass through the mesh's vertices and edges.
TEST(SignedDistance, GridSurfaceOfASphereMeshLiesOnIt) {
  Mesh sphere;
  {
    ScalarGrid analytic = empty_grid(33, 0.0625f);
    analytic.values.resize(size_t(33 * 33 * 33));
    for (int z = 0; z < 33; ++z)
      for (int y = 0; y < 33; ++y)
        for (int x = 0; x < 33; ++x)
          analytic.values[analytic.index(x, y, z)] = 0.7f - analytic.position(x, y, z).norm();
    sphere = extract_zero_surface(analytic);  // vertices on the sample grid's lines
  }
  ScalarGrid grid = empty_grid(33, 0.0625f);  // the same grid: columns through the mesh's vertices
  sample_signed_distance(sphere, 0.2f, grid);
  const Mesh surface = extract_zero_surface(grid);
  const MeshTopology topo = mesh_topology(surface);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_NEAR(topo.volume / mesh_topology(sphere).volume, 1.0, 0.02);
  for (const Vec3f& p : surface.positions) ASSERT_NEAR(p.norm(), 0.7f, 0.02f);
}

TEST(SignedDistance, BadInputsAreErrors) {
  ScalarGrid grid = empty_grid(4, 0.5f);
  EXPECT_THROW(sample_signed_distance(box_mesh(kLo, kHi), 0.f, grid), Error);
  EXPECT_THROW(sample_signed_distance(Mesh{}, 0.1f, grid), Error);
}

}  // namespace
}  // namespace u3d
