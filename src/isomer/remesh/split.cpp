#include "isomer/remesh/split.h"

#include "geometry/edge_topology.h"

namespace u3d {

int split_long_edges(VertexRows& rows, std::vector<Vec3i>& faces, const EdgeTopology& t,
                     std::vector<float>& max_edge_length) {
  std::vector<int> midpoint(t.edge_count(), -1);
  int splits = 0;
  for (size_t e = 0; e < t.edge_count(); ++e) {
    const int a = t.edge_vertices[e][0], b = t.edge_vertices[e][1];
    const float limit = 0.5f * (max_edge_length[a] + max_edge_length[b]);
    if ((rows.position(a) - rows.position(b)).norm() <= limit) continue;
    midpoint[e] = rows.append_mean(a, b);
    max_edge_length.push_back(limit);
    ++splits;
  }
  if (splits == 0) return 0;
  const size_t original = faces.size();
  for (size_t f = 0; f < original; ++f) {
    const Vec3i c = faces[f];
    const int m[3] = {midpoint[t.face_edges[f][0]], midpoint[t.face_edges[f][1]], midpoint[t.face_edges[f][2]]};
    const int count = (m[0] >= 0) + (m[1] >= 0) + (m[2] >= 0);
    if (count == 0) continue;
    if (count == 3) {
      faces[f] = {c[0], m[0], m[2]};
      faces.push_back({m[0], c[1], m[1]});
      faces.push_back({m[2], m[1], c[2]});
      faces.push_back({m[0], m[1], m[2]});
      continue;
    }
    if (count == 1) {
      const int r = m[0] >= 0 ? 0 : m[1] >= 0 ? 1 : 2;  // split side r: corner r -> r + 1
      const int c0 = c[r], c1 = c[(r + 1) % 3], c2 = c[(r + 2) % 3];
      faces[f] = {c0, m[r], c2};
      faces.push_back({m[r], c1, c2});
      continue;
    }
    // Two split sides: rotate so the unsplit one is side 2 (corner 2 -> corner 0).
    const int r = m[0] < 0 ? 1 : m[1] < 0 ? 2 : 0;
    const int c0 = c[r], c1 = c[(r + 1) % 3], c2 = c[(r + 2) % 3];
    const int m0 = m[r], m1 = m[(r + 1) % 3];
    faces[f] = {m0, c1, m1};
    // The remaining quad c0, m0, m1, c2 is cut along its shorter diagonal.
    if ((rows.position(c0) - rows.position(m1)).norm() <= (rows.position(m0) - rows.position(c2)).norm()) {
      faces.push_back({c0, m0, m1});
      faces.push_back({c0, m1, c2});
    } else {
      faces.push_back({c0, m0, c2});
      faces.push_back({m0, m1, c2});
    }
  }
  return splits;
}

}  // namespace u3d
