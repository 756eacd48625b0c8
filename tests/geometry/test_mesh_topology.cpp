#include "geometry/mesh_topology.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "geometry/icosphere.h"

namespace {

using u3d::Mesh;
using u3d::mesh_topology;
using u3d::Vec3f;
using u3d::Vec3i;

Mesh tetrahedron(const Vec3f& offset, int first_vertex, Mesh m = {}) {
  for (const Vec3f& p : {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, 0, 1)}) m.positions.push_back(p + offset);
  const int a = first_vertex;
  for (const Vec3i& f : {Vec3i(0, 2, 1), Vec3i(0, 1, 3), Vec3i(0, 3, 2), Vec3i(1, 2, 3)})
    m.faces.push_back(Vec3i(a + f[0], a + f[1], a + f[2]));
  return m;
}

TEST(MeshTopology, ClosedSphereIsOneGenusZeroPiece) {
  const auto t = mesh_topology(u3d::make_icosphere(3, 1.f));
  EXPECT_TRUE(t.closed_manifold());
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_NEAR(t.volume, 4.0 / 3.0 * 3.14159265, 0.1);
}

TEST(MeshTopology, CountsPiecesAndReversedOrientation) {
  Mesh two = tetrahedron(Vec3f(3, 0, 0), 4, tetrahedron(Vec3f(0, 0, 0), 0));
  auto t = mesh_topology(two);
  EXPECT_TRUE(t.closed_manifold());
  EXPECT_EQ(t.components, 2);
  EXPECT_EQ(t.euler_characteristic, 4);
  EXPECT_NEAR(t.volume, 2.0 / 6.0, 1e-9);
  for (Vec3i& f : two.faces) std::swap(f[1], f[2]);
  EXPECT_NEAR(mesh_topology(two).volume, -2.0 / 6.0, 1e-9);
}

TEST(MeshTopology, MissingFaceOpensTheSurface) {
  Mesh m = u3d::make_icosphere(2, 1.f);
  m.faces.pop_back();
  const auto t = mesh_topology(m);
  EXPECT_FALSE(t.watertight);
  EXPECT_TRUE(t.edge_manifold);
  EXPECT_TRUE(t.vertex_manifold);  // the border vertices keep one (open) fan each
  EXPECT_FALSE(t.closed_manifold());
}

TEST(MeshTopology, TwoPiecesSharingOneVertexArePinched) {
  Mesh m = tetrahedron(Vec3f(0, 0, 0), 0);
  m.positions.push_back(Vec3f(-1, 0, 0));
  m.positions.push_back(Vec3f(0, -1, 0));
  m.positions.push_back(Vec3f(0, 0, -1));
  // A second tetrahedron on vertex 0 and three new ones.
  for (const Vec3i& f : {Vec3i(0, 4, 5), Vec3i(0, 6, 4), Vec3i(0, 5, 6), Vec3i(4, 6, 5)}) m.faces.push_back(f);
  const auto t = mesh_topology(m);
  EXPECT_TRUE(t.edge_manifold);
  EXPECT_TRUE(t.watertight);
  EXPECT_FALSE(t.vertex_manifold);
  EXPECT_EQ(t.components, 2);  // joined by edges only
}

TEST(MeshTopology, ThirdFaceOnAnEdgeIsNotManifold) {
  Mesh m = tetrahedron(Vec3f(0, 0, 0), 0);
  m.positions.push_back(Vec3f(1, 1, 1));
  m.faces.push_back(Vec3i(1, 2, 4));  // the edge 1-2 now has three faces
  const auto t = mesh_topology(m);
  EXPECT_FALSE(t.edge_manifold);
  EXPECT_FALSE(t.closed_manifold());
}

TEST(MeshTopology, RejectsAFaceWithAMissingVertex) {
  Mesh m = tetrahedron(Vec3f(0, 0, 0), 0);
  m.faces.push_back(Vec3i(0, 1, 7));
  EXPECT_THROW(mesh_topology(m), u3d::Error);
}

}  // namespace
