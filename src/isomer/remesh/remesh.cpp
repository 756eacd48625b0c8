#include "isomer/remesh/remesh.h"

#include <algorithm>

#include "isomer/remesh/collapse.h"
#include "isomer/remesh/flip.h"
#include "isomer/remesh/split.h"

namespace u3d {

std::vector<int> drop_unreferenced_vertices(VertexRows& rows, std::vector<Vec3i>& faces) {
  const size_t n = rows.count();
  std::vector<int> new_index(n, -1);
  for (const Vec3i& f : faces)
    for (int i = 0; i < 3; ++i) new_index[f[i]] = 0;
  std::vector<int> old_index;
  for (size_t v = 0; v < n; ++v) {
    if (new_index[v] < 0) continue;
    new_index[v] = int(old_index.size());
    if (size_t(new_index[v]) != v)
      std::copy_n(rows.row(v), rows.stride, rows.row(size_t(new_index[v])));
    old_index.push_back(int(v));
  }
  rows.values.resize(old_index.size() * size_t(rows.stride));
  for (Vec3i& f : faces)
    for (int i = 0; i < 3; ++i) f[i] = new_index[f[i]];
  return old_index;
}

RemeshCounts remesh_pass(VertexRows& rows, std::vector<Vec3i>& faces, std::vector<float> min_edge_length,
                         std::vector<float> max_edge_length, bool flip, std::mt19937& rng, size_t max_vertices,
                         TopologyCache* cache) {
  TopologyCache local;
  TopologyCache& topology = cache ? *cache : local;
  RemeshCounts counts;
  counts.collapses = collapse_short_edges(rows, faces, topology.of(faces, rows.count()), min_edge_length, rng);
  if (counts.collapses > 0) topology.invalidate();
  if (rows.count() < max_vertices) {
    counts.splits = split_long_edges(rows, faces, topology.of(faces, rows.count()), max_edge_length);
    if (counts.splits > 0) topology.invalidate();
  }
  // Collapses leave their removed vertices unreferenced: renumbering invalidates the topology too.
  const size_t before = rows.count();
  drop_unreferenced_vertices(rows, faces);
  if (rows.count() != before) topology.invalidate();
  if (flip) counts.flips = flip_edges_for_valence(rows, faces, topology.of(faces, rows.count()));
  return counts;
}

}  // namespace u3d
