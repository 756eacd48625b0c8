#include "isomer/remesh/collapse.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <numeric>

#include "geometry/edge_topology.h"

namespace u3d {

namespace {

// Edge (a, b) may collapse without breaking the manifold when a and b share exactly the two
// neighbours opposite the edge, and those keep a valence of at least 3.
bool link_condition_holds(const EdgeTopology& t, int e, const std::vector<Vec3i>& faces) {
  if (!t.interior(e)) return false;
  const int a = t.edge_vertices[e][0], b = t.edge_vertices[e][1];
  int shared = 0;
  for (int k = t.ring_offsets[a]; k < t.ring_offsets[a + 1]; ++k)
    if (t.adjacent(b, t.ring[k])) ++shared;
  if (shared != 2) return false;
  for (int s : t.edge_sides[e]) {
    const int opposite = faces[s / 3][(s % 3 + 2) % 3];
    if (t.degree(opposite) <= 3) return false;
  }
  return true;
}

}  // namespace

int collapse_short_edges(VertexRows& rows, std::vector<Vec3i>& faces, const EdgeTopology& t,
                         const std::vector<float>& min_edge_length, std::mt19937& rng,
                         const CollapseOptions& options) {
  const size_t n = rows.count();
  if (faces.size() <= 4) return 0;
  const size_t edges = t.edge_count();
  std::vector<float> length(edges);
  for (size_t e = 0; e < edges; ++e)
    length[e] = (rows.position(t.edge_vertices[e][0]) - rows.position(t.edge_vertices[e][1])).norm();

  // Faces flipped against their vertex normals, or tiny, each nominate one of their edges.
  std::vector<Vec3f> face_normal(faces.size());
  std::vector<Vec3f> vertex_normal(n, Vec3f::Zero());
  for (size_t f = 0; f < faces.size(); ++f) {
    const Vec3f p0 = rows.position(faces[f][0]);
    face_normal[f] = (rows.position(faces[f][1]) - p0).cross(rows.position(faces[f][2]) - p0);
    for (int i = 0; i < 3; ++i) vertex_normal[faces[f][i]] += face_normal[f];
  }
  for (Vec3f& v : vertex_normal) v.normalize();
  std::vector<float> priority(edges, 0.f);
  const int draw_limit = int(std::lround(2.f / (1.f - options.shortest_probability)));
  std::uniform_int_distribution<int> draw(0, std::max(draw_limit - 1, 0));
  for (size_t f = 0; f < faces.size(); ++f) {
    const Vec3i& c = faces[f];
    const Vec3f reference = vertex_normal[c[0]] + vertex_normal[c[1]] + vertex_normal[c[2]];
    const float min_len = (min_edge_length[c[0]] + min_edge_length[c[1]] + min_edge_length[c[2]]) / 3.f;
    const bool flipped = face_normal[f].dot(reference) < 0.f;
    const bool tiny = face_normal[f].norm() < 2.f * options.area_ratio * min_len * min_len;
    if (!flipped && !tiny) continue;
    // Sides by decreasing length; rank 2 (the shortest) is the most likely pick.
    std::array<int, 3> order = {0, 1, 2};
    std::sort(order.begin(), order.end(),
              [&](int x, int y) { return length[t.face_edges[f][x]] > length[t.face_edges[f][y]]; });
    const int pick = std::min(draw(rng), 2);
    priority[t.face_edges[f][order[pick]]] += 1.f;
  }
  for (size_t e = 0; e < edges; ++e) {
    const auto& ev = t.edge_vertices[e];
    const float min_len = 0.5f * (min_edge_length[ev[0]] + min_edge_length[ev[1]]);
    priority[e] += std::max(0.f, 1.f - length[e] / min_len);
  }

  std::vector<int> candidates;
  for (size_t e = 0; e < edges; ++e)
    if (priority[e] > 0.f) candidates.push_back(int(e));
  std::stable_sort(candidates.begin(), candidates.end(), [&](int x, int y) { return priority[x] > priority[y]; });

  // Accepted collapses have disjoint closed one-rings, so each one's link check stays valid.
  std::vector<char> touched(n, 0);
  std::vector<int> target(n);
  std::iota(target.begin(), target.end(), 0);
  int collapses = 0;
  size_t live_vertices = 0;
  for (size_t v = 0; v < n; ++v) live_vertices += t.degree(int(v)) > 0;
  auto ring_free = [&](int v) {
    if (touched[v]) return false;
    for (int k = t.ring_offsets[v]; k < t.ring_offsets[v + 1]; ++k)
      if (touched[t.ring[k]]) return false;
    return true;
  };
  for (int e : candidates) {
    if (live_vertices - collapses <= 4) break;  // keep at least a tetrahedron
    const int a = t.edge_vertices[e][0], b = t.edge_vertices[e][1];
    if (!ring_free(a) || !ring_free(b) || !link_condition_holds(t, e, faces)) continue;
    for (int v : {a, b}) {
      touched[v] = 1;
      for (int k = t.ring_offsets[v]; k < t.ring_offsets[v + 1]; ++k) touched[t.ring[k]] = 1;
    }
    rows.average_into(a, b);
    target[b] = a;
    ++collapses;
  }
  if (collapses == 0) return 0;
  size_t kept = 0;
  for (Vec3i f : faces) {
    for (int i = 0; i < 3; ++i) f[i] = target[f[i]];
    if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0]) continue;  // the two faces of a collapsed edge
    faces[kept++] = f;
  }
  faces.resize(kept);
  return collapses;
}

}  // namespace u3d
