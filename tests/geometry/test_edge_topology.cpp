// The shared edge topology's side lists and the closed-manifold check built on it.
#include "geometry/edge_topology.h"

#include <gtest/gtest.h>

#include "geometry/manifold_check.h"

namespace {

using u3d::EdgeSideLists;
using u3d::EdgeTopology;
using u3d::Vec3i;

const std::vector<Vec3i> kTetrahedron = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

bool mentions(const std::string& problem, const std::string& what) { return problem.find(what) != std::string::npos; }

TEST(EdgeTopology, SideListsHoldEveryFaceOfAnEdge) {
  // The edge 0-1 has three faces (two run 0 -> 1, one 1 -> 0); 1-2 has two opposite ones; 1-5 one.
  const std::vector<Vec3i> faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {2, 1, 5}};
  const EdgeTopology t = u3d::build_edge_topology(faces, 6);
  const EdgeSideLists l = u3d::edge_side_lists(t);
  ASSERT_EQ(l.edge_count(), t.edge_count());
  const int crowded = t.face_edges[0][0], shared = t.face_edges[0][1], border = t.face_edges[3][1];
  EXPECT_FALSE(t.edge_manifold[crowded]);
  EXPECT_FALSE(t.border(crowded));
  ASSERT_EQ(l.count(crowded), 3);
  EXPECT_EQ(l.sides[l.offsets[crowded]], 0);
  EXPECT_EQ(l.sides[l.offsets[crowded] + 1], 3);
  EXPECT_EQ(l.sides[l.offsets[crowded] + 2], 6);
  EXPECT_TRUE(t.interior(shared));
  EXPECT_EQ(l.count(shared), 2);
  EXPECT_TRUE(t.border(border));
  EXPECT_EQ(l.count(border), 1);
  EXPECT_EQ(l.sides.size(), faces.size() * 3);
}

TEST(ManifoldCheck, NamesTheProblem) {
  EXPECT_EQ(u3d::closed_manifold_problem(kTetrahedron, 4), "");
  EXPECT_TRUE(mentions(u3d::closed_manifold_problem({kTetrahedron.begin(), kTetrahedron.end() - 1}, 4), "border"));
  EXPECT_TRUE(mentions(u3d::closed_manifold_problem(kTetrahedron, 5), "unreferenced"));
  std::vector<Vec3i> faces = kTetrahedron;
  faces.push_back({1, 2, 4});  // a fin on the edge 1-2
  EXPECT_TRUE(mentions(u3d::closed_manifold_problem(faces, 5), "used twice"));
  faces = kTetrahedron;
  for (const Vec3i& f : kTetrahedron)  // a second tetrahedron on vertex 0 only
    faces.push_back(Vec3i(f[0] ? f[0] + 3 : 0, f[1] ? f[1] + 3 : 0, f[2] ? f[2] + 3 : 0));
  EXPECT_TRUE(mentions(u3d::closed_manifold_problem(faces, 7), "pinched"));
  faces = kTetrahedron;
  faces.push_back({1, 1, 2});
  EXPECT_TRUE(mentions(u3d::closed_manifold_problem(faces, 4), "degenerate"));
  faces.back() = {1, 2, 4};
  EXPECT_TRUE(mentions(u3d::closed_manifold_problem(faces, 4), "bad index"));
}

}  // namespace
