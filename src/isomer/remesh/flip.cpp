#include "isomer/remesh/flip.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>

#include "geometry/edge_topology.h"

namespace u3d {

namespace {

// After faces `left` and `right` (the two sides of edge e) were replaced by the flipped pair: the
// four outer edges keep their numbers and direction of travel but change face, and e becomes the new
// diagonal. `old_edges` are the edges of the two faces' sides before the flip.
void patch_flipped_edge(EdgeTopology& t, const std::vector<Vec3i>& faces, int e, int left, int right,
                        const std::array<int, 6>& old_edges) {
  for (const int f : {left, right})
    for (int i = 0; i < 3; ++i) {
      const int u = faces[f][i], v = faces[f][(i + 1) % 3];
      const std::array<int, 2> key = {std::min(u, v), std::max(u, v)};
      int edge = e;  // the one side found among no old edge is the new diagonal
      for (const int old : old_edges)
        if (old != e && t.edge_vertices[old] == key) edge = old;
      t.face_edges[f][i] = edge;
      t.edge_sides[edge][u == key[0] ? 0 : 1] = f * 3 + i;
    }
}

}  // namespace

int flip_edges_for_valence(const VertexRows& rows, std::vector<Vec3i>& faces, EdgeTopology& t) {
  struct Candidate {
    int edge;
    int gain;  // change of sum (valence - 6)^2, halved; negative is better
  };
  std::vector<Candidate> candidates;
  auto opposite = [&](int side) { return faces[side / 3][(side % 3 + 2) % 3]; };
  for (size_t e = 0; e < t.edge_count(); ++e) {
    if (!t.interior(int(e))) continue;
    const int a = t.edge_vertices[e][0], b = t.edge_vertices[e][1];
    const int cl = opposite(t.edge_sides[e][0]), cr = opposite(t.edge_sides[e][1]);
    // (d+1-6)^2 - (d-6)^2 summed over the two gaining and two losing vertices, divided by 2.
    const int gain = 2 + t.degree(cl) + t.degree(cr) - t.degree(a) - t.degree(b);
    if (gain < 0) candidates.push_back({int(e), gain});
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& x, const Candidate& y) { return x.gain < y.gain; });
  std::vector<char> used(rows.count(), 0);
  int flips = 0;
  for (const Candidate& c : candidates) {
    const int a = t.edge_vertices[c.edge][0], b = t.edge_vertices[c.edge][1];
    const int left = t.edge_sides[c.edge][0] / 3, right = t.edge_sides[c.edge][1] / 3;
    const int cl = opposite(t.edge_sides[c.edge][0]), cr = opposite(t.edge_sides[c.edge][1]);
    if (used[a] || used[b] || used[cl] || used[cr]) continue;
    if (cl == cr || t.adjacent(cl, cr) || t.degree(a) <= 3 || t.degree(b) <= 3) continue;
    // Left face is (a, b, cl), right face (b, a, cr); the new pair must face the same way as the old.
    const Vec3f pa = rows.position(a), pb = rows.position(b), pl = rows.position(cl), pr = rows.position(cr);
    const Vec3f old_normal = (pb - pa).cross(pl - pa) + (pr - pa).cross(pb - pa);
    if (old_normal.dot((pr - pa).cross(pl - pa)) <= 0.f || old_normal.dot((pl - pb).cross(pr - pb)) <= 0.f) continue;
    const std::array<int, 6> old_edges = {t.face_edges[left][0],  t.face_edges[left][1],  t.face_edges[left][2],
                                          t.face_edges[right][0], t.face_edges[right][1], t.face_edges[right][2]};
    faces[left] = {a, cr, cl};
    faces[right] = {b, cl, cr};
    t.edge_vertices[c.edge] = {std::min(cl, cr), std::max(cl, cr)};
    patch_flipped_edge(t, faces, c.edge, left, right, old_edges);
    used[a] = used[b] = used[cl] = used[cr] = 1;
    ++flips;
  }
  // Later candidates only read the rings of vertices no flip touched (any other is `used`), so the
  // rings are brought up to date once, here.
  if (flips > 0) rebuild_rings(t, rows.count());
  return flips;
}

}  // namespace u3d
