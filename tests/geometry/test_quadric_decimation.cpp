// Quadric decimation keeps a closed manifold closed, oriented and close to the original surface.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <algorithm>
#include <array>
#include <map>

#include "geometry/icosphere.h"
#include "geometry/manifold_check.h"
#include "geometry/mesh_topology.h"
#include "geometry/quadric_decimation.h"

namespace u3d {
namespace {

// Every edge used once in each direction, every vertex a single fan.
bool closed_and_oriented(const Mesh& m) { return closed_manifold_problem(m.faces, m.positions.size()).empty(); }

TEST(QuadricDecimation, SphereStaysClosedAndRound) {
  const Mesh sphere = make_icosphere(5, 0.8f);  // 20,480 faces
  const Mesh small = decimate_closed_mesh(sphere, 2000);
  EXPECT_LE(small.face_count(), 2000u);
  EXPECT_GE(small.face_count(), 1990u);
  EXPECT_TRUE(closed_and_oriented(small));
  const MeshTopology topo = mesh_topology(small);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.euler_characteristic, 2);
  for (const Vec3f& p : small.positions) EXPECT_NEAR(p.norm(), 0.8f, 0.01f);
  EXPECT_NEAR(topo.volume, mesh_topology(sphere).volume, 0.01 * mesh_topology(sphere).volume);
}

// The unit cube with every side an n x n grid of squares (two triangles each), outward.
Mesh gridded_cube(int n) {
  Mesh cube;
  std::map<std::array<int, 3>, int> index;  // vertex by integer grid coordinates in [0, n]^3
  auto vertex = [&](const std::array<int, 3>& g) {
    auto [it, added] = index.try_emplace(g, int(cube.positions.size()));
    if (added) cube.positions.push_back(Vec3f(float(g[0]), float(g[1]), float(g[2])) / float(n) - Vec3f::Constant(0.5f));
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side <= n; side += n)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const int u = (axis + 1) % 3, v = (axis + 2) % 3;
          auto corner = [&](int di, int dj) {
            std::array<int, 3> g;
            g[axis] = side, g[u] = i + di, g[v] = j + dj;
            return vertex(g);
          };
          Vec3i a(corner(0, 0), corner(1, 0), corner(1, 1)), b(corner(0, 0), corner(1, 1), corner(0, 1));
          if (side == 0) std::swap(a[1], a[2]), std::swap(b[1], b[2]);  // (u, v, axis) is right-handed
          cube.faces.push_back(a);
          cube.faces.push_back(b);
        }
  return cube;
}

// Flat sides collapse freely; the corners and the straight edges survive (their quadrics pin them),
// so the volume stays exactly 1.
TEST(QuadricDecimation, FlatSidesCollapseCornersStay) {
  const Mesh cube = gridded_cube(12);  // 1,728 faces
  ASSERT_NEAR(mesh_topology(cube).volume, 1.0, 1e-6);
  ASSERT_TRUE(closed_and_oriented(cube));
  const Mesh small = decimate_closed_mesh(cube, 12);
  EXPECT_TRUE(closed_and_oriented(small));
  EXPECT_TRUE(mesh_topology(small).closed_manifold());
  EXPECT_LE(small.face_count(), 40u);
  EXPECT_NEAR(mesh_topology(small).volume, 1.0, 1e-4);
  for (const Vec3f& p : small.positions) EXPECT_NEAR(p.cwiseAbs().maxCoeff(), 0.5f, 1e-5f);
}

// Zero-cost collapses on a flat side must not pile up into one fan: every vertex keeps at most 16
// neighbours (the input's are at most 6), and the volume is exact on the way down.
TEST(QuadricDecimation, FlatSidesDoNotBecomeFans) {
  const Mesh cube = gridded_cube(40);  // 19,200 faces
  const Mesh small = decimate_closed_mesh(cube, 2000);
  EXPECT_EQ(small.face_count(), 2000u);
  EXPECT_TRUE(closed_and_oriented(small));
  EXPECT_NEAR(mesh_topology(small).volume, 1.0, 1e-4);
  std::vector<int> valence(small.vertex_count(), 0);
  for (const Vec3i& f : small.faces)
    for (int k = 0; k < 3; ++k) ++valence[f[k]];  // closed manifold: faces around a vertex = neighbours
  EXPECT_LE(*std::max_element(valence.begin(), valence.end()), 16);
}

TEST(QuadricDecimation, TargetAboveFaceCountChangesNothing) {
  const Mesh sphere = make_icosphere(2, 1.f);
  const Mesh same = decimate_closed_mesh(sphere, sphere.face_count());
  EXPECT_EQ(same.face_count(), sphere.face_count());
  EXPECT_EQ(same.vertex_count(), sphere.vertex_count());
}

}  // namespace
}  // namespace u3d
