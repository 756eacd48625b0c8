#include "geometry/loop_subdivision.h"

#include "geometry/edge_topology.h"

namespace u3d {

Mesh loop_subdivide(const Mesh& mesh) {
  const size_t nv = mesh.positions.size();
  const EdgeTopology t = build_edge_topology(mesh.faces, nv);
  const std::vector<Vec3f>& p = mesh.positions;
  auto opposite = [&](int side) { return mesh.faces[side / 3][(side % 3 + 2) % 3]; };

  Mesh out;
  out.positions.resize(nv + t.edge_count());
  // Vertices on an irregular edge (border or more than two faces) are creases: they keep their place.
  std::vector<char> crease(nv, 0);
  for (size_t e = 0; e < t.edge_count(); ++e) {
    const auto [a, b] = t.edge_vertices[e];
    if (t.interior(int(e))) {
      const Vec3f c = p[opposite(t.edge_sides[e][0])], d = p[opposite(t.edge_sides[e][1])];
      out.positions[nv + e] = 0.375f * (p[a] + p[b]) + 0.125f * (c + d);
    } else {
      out.positions[nv + e] = 0.5f * (p[a] + p[b]);
      crease[a] = crease[b] = 1;
    }
  }
  for (size_t v = 0; v < nv; ++v) {
    const int n = t.degree(int(v));
    if (crease[v] || n < 3) {
      out.positions[v] = p[v];
      continue;
    }
    const float beta = n == 3 ? 3.f / 16.f : 3.f / (8.f * float(n));
    Vec3f ring_sum = Vec3f::Zero();
    for (int k = t.ring_offsets[v]; k < t.ring_offsets[v + 1]; ++k) ring_sum += p[t.ring[k]];
    out.positions[v] = (1.f - float(n) * beta) * p[v] + beta * ring_sum;
  }
  out.faces.reserve(mesh.faces.size() * 4);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Vec3i& c = mesh.faces[f];
    // m[i]: new vertex on side i (corner i -> corner i + 1).
    const Vec3i m = t.face_edges[f] + Vec3i::Constant(int(nv));
    out.faces.push_back({c[0], m[0], m[2]});
    out.faces.push_back({c[1], m[1], m[0]});
    out.faces.push_back({c[2], m[2], m[1]});
    out.faces.push_back({m[0], m[1], m[2]});
  }
  return out;
}

}  // namespace u3d
