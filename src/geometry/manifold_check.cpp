#include "geometry/manifold_check.h"

#include <map>
#include <utility>

namespace u3d {

std::string closed_manifold_problem(const std::vector<Vec3i>& faces, size_t vertex_count) {
  std::map<std::pair<int, int>, int> directed;  // directed edge -> count
  std::vector<std::vector<std::pair<int, int>>> fan(vertex_count);  // per vertex: (next, prev) of each face
  for (size_t f = 0; f < faces.size(); ++f) {
    const Vec3i& c = faces[f];
    for (int i = 0; i < 3; ++i) {
      if (c[i] < 0 || size_t(c[i]) >= vertex_count) return "face " + std::to_string(f) + " has a bad index";
      if (c[i] == c[(i + 1) % 3]) return "face " + std::to_string(f) + " is degenerate";
      if (++directed[{c[i], c[(i + 1) % 3]}] > 1)
        return "edge " + std::to_string(c[i]) + "->" + std::to_string(c[(i + 1) % 3]) + " is used twice";
      fan[c[i]].push_back({c[(i + 1) % 3], c[(i + 2) % 3]});
    }
  }
  for (const auto& [edge, count] : directed)
    if (!directed.count({edge.second, edge.first}))
      return "edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) + " is a border";
  for (size_t v = 0; v < vertex_count; ++v) {
    if (fan[v].empty()) return "vertex " + std::to_string(v) + " is unreferenced";
    // Walk the fan: each face's `next` vertex is the `prev` vertex of the following face.
    std::map<int, int> by_prev;
    for (const auto& [next, prev] : fan[v]) by_prev[prev] = next;
    size_t steps = 0;
    int cursor = fan[v][0].first;
    do {
      auto it = by_prev.find(cursor);
      if (it == by_prev.end()) return "vertex " + std::to_string(v) + " has an open fan";
      cursor = it->second;
      ++steps;
    } while (cursor != fan[v][0].first && steps <= fan[v].size());
    if (steps != fan[v].size()) return "vertex " + std::to_string(v) + " is pinched (several fans)";
  }
  return {};
}

}  // namespace u3d
