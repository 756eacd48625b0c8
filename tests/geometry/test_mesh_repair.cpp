// Repair closes holes and removes pinches, leaving a closed manifold with outward faces.
#include <gtest/gtest.h>

#include "geometry/mesh_repair.h"
#include "geometry/mesh_topology.h"

namespace u3d {
namespace {

// Closed UV sphere without duplicate pole vertices.
Mesh sphere(int rings, int segments) {
  Mesh m;
  m.positions.push_back(Vec3f(0, 1, 0));
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const float th = float(M_PI) * r / rings, ph = 2.f * float(M_PI) * s / segments;
      m.positions.push_back(Vec3f(std::sin(th) * std::sin(ph), std::cos(th), std::sin(th) * std::cos(ph)));
    }
  m.positions.push_back(Vec3f(0, -1, 0));
  const int bottom = int(m.positions.size()) - 1;
  auto at = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) {
    m.faces.push_back({0, at(1, s), at(1, s + 1)});
    m.faces.push_back({bottom, at(rings - 1, s + 1), at(rings - 1, s)});
    for (int r = 1; r + 1 < rings; ++r) {
      m.faces.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.faces.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  }
  return m;
}

TEST(MeshRepair, SphereIsAlreadyClosed) {
  Mesh m = sphere(8, 12);
  const MeshTopology t = mesh_topology(m);
  EXPECT_TRUE(t.closed_manifold()) << t.summary();
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_GT(t.volume, 0);
}

TEST(MeshRepair, FillsHolesIncludingTwoTouchingAtAVertex) {
  Mesh m = sphere(8, 12);
  // Two holes sharing vertex at(3, 0): remove faces on both sides of it (a pinch).
  const int pinch = 1 + 2 * 12;
  std::vector<Vec3i> kept;
  int removed = 0;
  for (const Vec3i& f : m.faces) {
    const bool touches = f[0] == pinch || f[1] == pinch || f[2] == pinch;
    if (touches && (removed == 0 || removed == 3)) {
      ++removed;
      continue;
    }
    if (touches) ++removed;
    kept.push_back(f);
  }
  m.faces = kept;
  m.faces.erase(m.faces.begin() + 40);  // and an ordinary one-face hole elsewhere
  ASSERT_FALSE(mesh_topology(m).closed_manifold());
  const MeshRepairReport r = repair_to_closed_manifold(m);
  const MeshTopology t = mesh_topology(m);
  EXPECT_TRUE(r.closed_manifold);
  EXPECT_TRUE(t.closed_manifold()) << t.summary();
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_GT(t.volume, 0);
  EXPECT_GE(r.holes_filled, 2u);
}

}  // namespace
}  // namespace u3d
