// Zero level sets of sampled fields: closed, consistently oriented outward, and where the field says.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>

#include "core/error.h"
#include "geometry/manifold_check.h"
#include "geometry/marching_tetrahedra.h"
#include "geometry/mesh_topology.h"

namespace u3d {
namespace {

// Every edge used once in each direction, every vertex a single fan.
bool closed_and_oriented(const Mesh& m) { return closed_manifold_problem(m.faces, m.positions.size()).empty(); }

// Samples f over [-1, 1]^3 with n samples per axis.
ScalarGrid sampled(int n, const std::function<float(const Vec3f&)>& f) {
  ScalarGrid g;
  g.nx = g.ny = g.nz = n;
  g.origin = Vec3f::Constant(-1.f);
  g.spacing = 2.f / float(n - 1);
  g.values.resize(size_t(n) * n * n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) g.values[g.index(x, y, z)] = f(g.position(x, y, z));
  return g;
}

TEST(MarchingTetrahedra, SphereIsClosedOutwardAndOnTheLevelSet) {
  const float r = 0.7f;
  const ScalarGrid grid = sampled(48, [&](const Vec3f& p) { return r - p.norm(); });
  const Mesh mesh = extract_zero_surface(grid);
  ASSERT_FALSE(mesh.faces.empty());
  EXPECT_TRUE(closed_and_oriented(mesh));
  const MeshTopology topo = mesh_topology(mesh);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler_characteristic, 2);
  // Positive volume = outward normals; the inscribed polyhedron loses a little volume.
  const double exact = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_GT(topo.volume, 0.97 * exact);
  EXPECT_LT(topo.volume, exact);
  // Vertices lie on grid edges where the linear interpolant crosses 0: within the chord error.
  for (const Vec3f& p : mesh.positions) EXPECT_NEAR(p.norm(), r, 0.25f * grid.spacing);
}

TEST(MarchingTetrahedra, TorusKeepsItsHole) {
  const ScalarGrid grid = sampled(56, [](const Vec3f& p) {
    const float ring = std::hypot(p.x(), p.z()) - 0.6f;
    return 0.25f - std::hypot(ring, p.y());
  });
  const Mesh mesh = extract_zero_surface(grid);
  EXPECT_TRUE(closed_and_oriented(mesh));
  const MeshTopology topo = mesh_topology(mesh);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.euler_characteristic, 0);  // genus 1
  EXPECT_GT(topo.volume, 0.0);
}

TEST(MarchingTetrahedra, SamplesExactlyZeroCountAsOutside) {
  // A field that is 0 on whole grid planes: the surface still closes and has no coincident vertices.
  ScalarGrid grid = sampled(9, [](const Vec3f& p) { return std::round(4.f * (0.5f - p.cwiseAbs().maxCoeff())) / 4.f; });
  const Mesh mesh = extract_zero_surface(grid);
  EXPECT_TRUE(closed_and_oriented(mesh));
  EXPECT_GT(mesh_topology(mesh).volume, 0.0);
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    for (size_t j = i + 1; j < mesh.positions.size(); ++j)
      EXPECT_GT((mesh.positions[i] - mesh.positions[j]).norm(), 1e-5f);
}

TEST(MarchingTetrahedra, EmptyFieldGivesEmptyMeshAndInsideBorderIsAnError) {
  EXPECT_TRUE(extract_zero_surface(sampled(8, [](const Vec3f&) { return -1.f; })).faces.empty());
  EXPECT_THROW(extract_zero_surface(sampled(8, [](const Vec3f& p) { return 1.5f - p.norm(); })), Error);
  ScalarGrid bad = sampled(8, [](const Vec3f&) { return -1.f; });
  bad.values.pop_back();
  EXPECT_THROW(extract_zero_surface(bad), Error);
}

}  // namespace
}  // namespace u3d
