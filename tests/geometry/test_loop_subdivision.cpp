// Our Loop subdivision against Open3D's SubdivideLoop (same rule, different vertex order) and the
// topology a step must give: four faces per face, V + E vertices, still closed and manifold.
#include <gtest/gtest.h>

#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>

#include "geometry/icosphere.h"
#include "geometry/loop_subdivision.h"
#include "geometry/mesh_topology.h"
#include "geometry/open3d_bridge.h"

namespace u3d {
namespace {

// Largest distance from a point of `a` to its nearest point of `b` (brute force: a few hundred points).
float farthest_unmatched(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  float worst = 0.f;
  for (const Vec3f& p : a) {
    float nearest = 1e30f;
    for (const Vec3f& q : b) nearest = std::min(nearest, (p - q).norm());
    worst = std::max(worst, nearest);
  }
  return worst;
}

Mesh irregular_closed_mesh() {
  Mesh mesh = make_icosphere(1, 0.7f);
  // Stretched and bent, so that a wrong weight shows.
  for (Vec3f& p : mesh.positions) p = Vec3f(p.x() * 1.3f + 0.2f * p.y(), p.y() * 0.8f, p.z() + 0.1f * p.x() * p.x());
  return mesh;
}

TEST(LoopSubdivision, MatchesOpen3D) {
  const Mesh mesh = irregular_closed_mesh();
  const Mesh ours = loop_subdivide(mesh);
  const auto theirs = to_open3d(mesh)->SubdivideLoop(1);
  ASSERT_EQ(ours.positions.size(), theirs->vertices_.size());
  ASSERT_EQ(ours.faces.size(), theirs->triangles_.size());
  const std::vector<Vec3f> b = from_open3d(*theirs).positions;
  EXPECT_LT(farthest_unmatched(ours.positions, b), 1e-5f);
  EXPECT_LT(farthest_unmatched(b, ours.positions), 1e-5f);
}

TEST(LoopSubdivision, KeepsTopologyAndOrientation) {
  Mesh mesh = make_icosphere(2, 1.f);
  const MeshTopology before = mesh_topology(mesh);
  const Mesh once = loop_subdivide(mesh);
  const MeshTopology after = mesh_topology(once);
  EXPECT_TRUE(after.closed_manifold()) << after.summary();
  EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
  EXPECT_EQ(once.faces.size(), mesh.faces.size() * 4);
  EXPECT_EQ(once.positions.size(), mesh.positions.size() + mesh.faces.size() * 3 / 2);
  // Loop shrinks a convex surface a little, never turns it inside out.
  EXPECT_GT(after.volume, 0.9 * before.volume);
  EXPECT_LT(after.volume, before.volume);
}

TEST(LoopSubdivision, BorderVerticesStay) {
  Mesh mesh = make_icosphere(1, 1.f);
  mesh.faces.pop_back();  // open one hole
  const Mesh once = loop_subdivide(mesh);
  const Vec3i removed = make_icosphere(1, 1.f).faces.back();
  for (int k = 0; k < 3; ++k) EXPECT_EQ(once.positions[removed[k]], mesh.positions[removed[k]]);
}

}  // namespace
}  // namespace u3d
