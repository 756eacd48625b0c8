#include "geometry/manifold_check.h"

#include "geometry/edge_topology.h"
#include "geometry/mesh_topology.h"

namespace u3d {

std::string closed_manifold_problem(const std::vector<Vec3i>& faces, size_t vertex_count) {
  for (size_t f = 0; f < faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      if (faces[f][i] < 0 || size_t(faces[f][i]) >= vertex_count)
        return "face " + std::to_string(f) + " has a bad index";
      if (faces[f][i] == faces[f][(i + 1) % 3]) return "face " + std::to_string(f) + " is degenerate";
    }
  const EdgeTopology topo = build_edge_topology(faces, vertex_count);
  for (size_t e = 0; e < topo.edge_count(); ++e) {
    const std::string edge = std::to_string(topo.edge_vertices[e][0]) + "-" + std::to_string(topo.edge_vertices[e][1]);
    // More than two sides, or two the same way, leave two sides in one direction.
    if (!topo.edge_manifold[e]) return "edge " + edge + " is used twice in one direction";
    if (topo.border(int(e))) return "edge " + edge + " is a border";
  }
  // With every edge closed and manifold, a vertex's fans are closed too: only their number is left.
  const std::vector<int> fans = vertex_fan_counts(faces, topo, vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    if (fans[v] == 0) return "vertex " + std::to_string(v) + " is unreferenced";
    if (fans[v] > 1) return "vertex " + std::to_string(v) + " is pinched (several fans)";
  }
  return {};
}

}  // namespace u3d
