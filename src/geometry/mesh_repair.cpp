#include "geometry/mesh_repair.h"

#include <open3d/geometry/TriangleMesh.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <set>

#include "geometry/disjoint_sets.h"
#include "geometry/edge_topology.h"
#include "geometry/mesh_topology.h"
#include "geometry/open3d_bridge.h"

namespace u3d {
namespace {

// Boundary edges are the directed face edges whose undirected edge has one face. Where a vertex
// starts more than one of them (two holes touching at a vertex) its faces are removed, widening the
// holes into simple loops; returns false then. Otherwise every simple boundary loop is closed by a
// fan around its centroid and the function returns true.
bool fill_boundary_loops(Mesh& mesh, size_t& faces_removed, size_t& holes_filled) {
  const EdgeTopology topo = build_edge_topology(mesh.faces, mesh.vertex_count());
  std::map<int, int> next;
  std::set<int> pinched;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      if (topo.border(topo.face_edges[f][k]) && !next.emplace(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3]).second)
        pinched.insert(mesh.faces[f][k]);
  if (!pinched.empty()) {
    const size_t before = mesh.faces.size();
    std::erase_if(mesh.faces, [&](const Vec3i& f) { return pinched.count(f[0]) || pinched.count(f[1]) || pinched.count(f[2]); });
    faces_removed += before - mesh.faces.size();
    return false;
  }
  while (!next.empty()) {
    std::vector<int> loop;
    const int start = next.begin()->first;
    int v = start;
    while (next.count(v)) {
      loop.push_back(v);
      const int w = next[v];
      next.erase(v);
      v = w;
    }
    if (v != start || loop.size() < 3) continue;  // not a closed loop: left for the next pass
    Vec3f centroid(0, 0, 0);
    for (int i : loop) centroid += mesh.positions[i];
    const int c = int(mesh.positions.size());
    mesh.positions.push_back(centroid / float(loop.size()));
    if (mesh.has_colors()) mesh.colors.push_back(mesh.colors[loop[0]]);
    for (size_t i = 0; i < loop.size(); ++i) mesh.faces.push_back({loop[(i + 1) % loop.size()], loop[i], c});
    ++holes_filled;
  }
  return true;
}

// Flips faces so that two faces sharing an edge traverse it in opposite directions: a breadth-first
// walk over each piece from its first face. Open3D's OrientTriangles ran before the holes were filled;
// this states the guarantee for the final faces, which the back-face-culling renderer relies on (a
// flipped face would vanish from its views). Edges with more than two faces do not link their faces.
void orient_consistently(Mesh& mesh, const EdgeSideLists& edges) {
  // Per face, its neighbours (by edge number) and whether the two agree as stored (opposite traversal).
  std::vector<std::vector<std::pair<int, bool>>> links(mesh.faces.size());
  for (size_t e = 0; e < edges.edge_count(); ++e) {
    if (edges.count(int(e)) != 2) continue;
    const int x = edges.sides[edges.offsets[e]], y = edges.sides[edges.offsets[e] + 1];
    const bool agree = mesh.faces[x / 3][x % 3] != mesh.faces[y / 3][y % 3];  // they start at different ends
    links[x / 3].push_back({y / 3, agree});
    links[y / 3].push_back({x / 3, agree});
  }
  std::vector<int8_t> flip(mesh.faces.size(), -1);  // -1 unvisited, else 0/1
  std::vector<int> queue;
  for (size_t seed = 0; seed < mesh.faces.size(); ++seed) {
    if (flip[seed] >= 0) continue;
    flip[seed] = 0;
    queue.assign(1, int(seed));
    while (!queue.empty()) {
      const int f = queue.back();
      queue.pop_back();
      for (const auto& [g, agree] : links[f]) {
        if (flip[g] >= 0) continue;
        flip[g] = int8_t(agree ? flip[f] : 1 - flip[f]);
        queue.push_back(g);
      }
    }
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (flip[f]) std::swap(mesh.faces[f][1], mesh.faces[f][2]);
}

// OrientTriangles makes each piece consistent but may turn a piece inside out: flip every piece whose
// enclosed volume is negative. Pieces are faces joined across every edge, non-manifold ones included.
void orient_outward(Mesh& mesh, const EdgeSideLists& edges) {
  DisjointSets pieces(mesh.faces.size());
  for (size_t e = 0; e < edges.edge_count(); ++e)
    for (int k = edges.offsets[e] + 1; k < edges.offsets[e + 1]; ++k) pieces.unite(edges.sides[k] / 3, edges.sides[k - 1] / 3);
  std::map<int, double> volume;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Vec3i& t = mesh.faces[f];
    volume[pieces.find(int(f))] += mesh.positions[t[0]].cast<double>().dot(
        mesh.positions[t[1]].cast<double>().cross(mesh.positions[t[2]].cast<double>()));
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (volume[pieces.find(int(f))] < 0) std::swap(mesh.faces[f][1], mesh.faces[f][2]);
}

}  // namespace

MeshRepairReport repair_to_closed_manifold(Mesh& mesh, int max_passes) {
  MeshRepairReport report;
  for (int pass = 0; pass < max_passes; ++pass) {
    auto o3d = to_open3d(mesh);
    o3d->RemoveDuplicatedVertices();
    o3d->RemoveDuplicatedTriangles();
    o3d->RemoveDegenerateTriangles();
    const size_t before = o3d->triangles_.size();
    o3d->RemoveNonManifoldEdges();
    // Bow-tie vertices: drop their faces, the holes are closed below.
    const std::vector<int> bad_vertices = o3d->GetNonManifoldVertices();
    if (!bad_vertices.empty()) {
      const std::set<int> bad(bad_vertices.begin(), bad_vertices.end());
      std::vector<bool> drop(o3d->triangles_.size(), false);
      for (size_t f = 0; f < drop.size(); ++f)
        for (int k = 0; k < 3; ++k) drop[f] = drop[f] || bad.count(o3d->triangles_[f][k]);
      o3d->RemoveTrianglesByMask(drop);
    }
    o3d->RemoveUnreferencedVertices();
    o3d->OrientTriangles();  // decimation can flip single faces
    report.faces_removed += before - o3d->triangles_.size();
    mesh = from_open3d(*o3d);
    fill_boundary_loops(mesh, report.faces_removed, report.holes_filled);
    if (mesh_topology(mesh).closed_manifold()) {
      report.closed_manifold = true;
      break;
    }
  }
  // Flipping faces keeps every edge and which faces meet there, so both passes share one edge list.
  const EdgeSideLists edges = edge_side_lists(build_edge_topology(mesh.faces, mesh.vertex_count()));
  orient_consistently(mesh, edges);
  orient_outward(mesh, edges);
  return report;
}

}  // namespace u3d
