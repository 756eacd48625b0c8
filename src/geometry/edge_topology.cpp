#include "geometry/edge_topology.h"

#include <algorithm>

namespace u3d {

bool EdgeTopology::adjacent(int a, int b) const {
  for (int k = ring_offsets[a]; k < ring_offsets[a + 1]; ++k)
    if (ring[k] == b) return true;
  return false;
}

EdgeTopology build_edge_topology(const std::vector<Vec3i>& faces, size_t vertex_count) {
  EdgeTopology t;
  const size_t sides = faces.size() * 3;
  // Bucket the face sides by their lower vertex (counting sort: linear time), then group each small
  // bucket by the higher vertex.
  std::vector<int> offsets(vertex_count + 1, 0);
  for (const Vec3i& f : faces)
    for (int i = 0; i < 3; ++i) ++offsets[std::min(f[i], f[(i + 1) % 3]) + 1];
  for (size_t v = 0; v < vertex_count; ++v) offsets[v + 1] += offsets[v];
  std::vector<std::pair<int, int>> bucket(sides);  // (higher vertex, side)
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (size_t f = 0; f < faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = faces[f][i], b = faces[f][(i + 1) % 3];
      bucket[fill[std::min(a, b)]++] = {std::max(a, b), int(f * 3 + i)};
    }
  t.face_edges.resize(faces.size());
  t.edge_vertices.reserve(sides / 2 + 1);
  t.edge_sides.reserve(sides / 2 + 1);
  t.edge_manifold.reserve(sides / 2 + 1);
  for (size_t lo = 0; lo < vertex_count; ++lo) {
    auto first = bucket.begin() + offsets[lo], last = bucket.begin() + offsets[lo + 1];
    std::sort(first, last);  // a handful of entries
    for (auto k = first; k != last;) {
      auto end = k;
      while (end != last && end->first == k->first) ++end;
      const int e = int(t.edge_vertices.size());
      t.edge_vertices.push_back({int(lo), k->first});
      std::array<int, 2> s = {EdgeTopology::kNone, EdgeTopology::kNone};
      bool manifold = end - k <= 2;
      for (auto j = k; j != end; ++j) {
        const int side = j->second;
        const int slot = faces[side / 3][side % 3] == int(lo) ? 0 : 1;
        if (s[slot] != EdgeTopology::kNone) manifold = false;
        s[slot] = side;
        t.face_edges[side / 3][side % 3] = e;
      }
      t.edge_sides.push_back(s);
      t.edge_manifold.push_back(manifold);
      k = end;
    }
  }
  rebuild_rings(t, vertex_count);
  return t;
}

void rebuild_rings(EdgeTopology& t, size_t vertex_count) {
  t.ring_offsets.assign(vertex_count + 1, 0);
  for (const auto& ev : t.edge_vertices) ++t.ring_offsets[ev[0] + 1], ++t.ring_offsets[ev[1] + 1];
  for (size_t v = 0; v < vertex_count; ++v) t.ring_offsets[v + 1] += t.ring_offsets[v];
  t.ring.resize(t.ring_offsets[vertex_count]);
  std::vector<int> fill(t.ring_offsets.begin(), t.ring_offsets.end() - 1);
  for (const auto& ev : t.edge_vertices) t.ring[fill[ev[0]]++] = ev[1], t.ring[fill[ev[1]]++] = ev[0];
}

EdgeSideLists edge_side_lists(const EdgeTopology& t) {
  EdgeSideLists l;
  l.offsets.assign(t.edge_count() + 1, 0);
  for (const Vec3i& fe : t.face_edges)
    for (int i = 0; i < 3; ++i) ++l.offsets[fe[i] + 1];
  for (size_t e = 0; e < t.edge_count(); ++e) l.offsets[e + 1] += l.offsets[e];
  l.sides.resize(t.face_edges.size() * 3);
  std::vector<int> fill(l.offsets.begin(), l.offsets.end() - 1);
  for (size_t f = 0; f < t.face_edges.size(); ++f)
    for (int i = 0; i < 3; ++i) l.sides[fill[t.face_edges[f][i]]++] = int(f * 3 + i);
  return l;
}

}  // namespace u3d
