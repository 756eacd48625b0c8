#include "isomer/remesh/edge_topology.h"

#include <algorithm>
#include <cstdint>

namespace u3d {

bool EdgeTopology::adjacent(int a, int b) const {
  for (int k = ring_offsets[a]; k < ring_offsets[a + 1]; ++k)
    if (ring[k] == b) return true;
  return false;
}

EdgeTopology build_edge_topology(const std::vector<Vec3i>& faces, size_t vertex_count) {
  EdgeTopology t;
  const size_t sides = faces.size() * 3;
  // Sort face sides by their undirected edge key.
  std::vector<std::pair<uint64_t, int>> keyed(sides);
  for (size_t f = 0; f < faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = faces[f][i], b = faces[f][(i + 1) % 3];
      const uint64_t key = (uint64_t(uint32_t(std::min(a, b))) << 32) | uint32_t(std::max(a, b));
      keyed[f * 3 + i] = {key, int(f * 3 + i)};
    }
  std::sort(keyed.begin(), keyed.end());
  t.face_edges.resize(faces.size());
  for (size_t k = 0; k < sides;) {
    size_t end = k;
    while (end < sides && keyed[end].first == keyed[k].first) ++end;
    const int e = int(t.edge_vertices.size());
    const int lo = int(keyed[k].first >> 32), hi = int(keyed[k].first & 0xffffffffu);
    t.edge_vertices.push_back({lo, hi});
    std::array<int, 2> s = {EdgeTopology::kNone, EdgeTopology::kNone};
    bool manifold = end - k <= 2;
    for (size_t j = k; j < end; ++j) {
      const int side = keyed[j].second;
      const int from = faces[side / 3][side % 3];
      const int slot = from == lo ? 0 : 1;
      if (s[slot] != EdgeTopology::kNone) manifold = false;
      s[slot] = side;
      t.face_edges[side / 3][side % 3] = e;
    }
    t.edge_sides.push_back(s);
    t.edge_manifold.push_back(manifold);
    k = end;
  }
  // Vertex rings from the unique edges.
  t.ring_offsets.assign(vertex_count + 1, 0);
  for (const auto& ev : t.edge_vertices) ++t.ring_offsets[ev[0] + 1], ++t.ring_offsets[ev[1] + 1];
  for (size_t v = 0; v < vertex_count; ++v) t.ring_offsets[v + 1] += t.ring_offsets[v];
  t.ring.resize(t.ring_offsets[vertex_count]);
  std::vector<int> fill(t.ring_offsets.begin(), t.ring_offsets.end() - 1);
  for (const auto& ev : t.edge_vertices) t.ring[fill[ev[0]]++] = ev[1], t.ring[fill[ev[1]]++] = ev[0];
  return t;
}

}  // namespace u3d
