// Edge neighbours of the antialias primitive: the third vertex of the face across each edge.
#include "render/antialias.h"

#include <gtest/gtest.h>

namespace {

using u3d::Vec3i;

// The face traversing b -> a, by a search over all faces; -1 when there is none.
int brute_force_opposite(const std::vector<Vec3i>& faces, int a, int b) {
  for (const Vec3i& g : faces)
    for (int k = 0; k < 3; ++k)
      if (g[k] == b && g[(k + 1) % 3] == a) return g[(k + 2) % 3];
  return -1;
}

TEST(EdgeNeighbors, ThirdVertexAcrossEachEdgeAndNoneOnBorders) {
  // A tetrahedron without one face (three border edges), and a face on 4-5 that runs the same way as
  // its neighbour (no neighbour either).
  const std::vector<Vec3i> faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {4, 5, 6}, {4, 5, 7}};
  const u3d::EdgeNeighbors n = u3d::edge_neighbors(faces, u3d::build_edge_topology(faces, 8));
  ASSERT_EQ(n.opposite.size(), faces.size());
  int borders = 0;
  for (size_t f = 0; f < faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      const int expected = brute_force_opposite(faces, faces[f][(i + 1) % 3], faces[f][(i + 2) % 3]);
      EXPECT_EQ(n.opposite[f][i], expected) << "face " << f << " corner " << i;
      borders += expected < 0;
    }
  EXPECT_EQ(borders, 3 + 6);
}

}  // namespace
