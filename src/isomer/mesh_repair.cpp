#include "isomer/mesh_repair.h"

#include <open3d/geometry/TriangleMesh.h>

#include <map>
#include <set>

#include "isomer/mesh_topology.h"
#include "isomer/open3d_bridge.h"

namespace u3d {
namespace {

// Closes every boundary loop with a centroid fan. Boundary edges are the directed face edges whose
// undirected edge has one face; in a manifold mesh each boundary vertex starts exactly one.
size_t fill_boundary_loops(Mesh& mesh) {
  std::map<std::pair<int, int>, int> uses;  // undirected edge -> face count
  for (const Vec3i& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(f[k], f[(k + 1) % 3])];
  std::map<int, int> next;
  for (const Vec3i& f : mesh.faces)
    for (int k = 0; k < 3; ++k)
      if (uses[std::minmax(f[k], f[(k + 1) % 3])] == 1) next[f[k]] = f[(k + 1) % 3];
  size_t filled = 0;
  while (!next.empty()) {
    std::vector<int> loop;
    int v = next.begin()->first;
    while (next.count(v)) {
      loop.push_back(v);
      const int w = next[v];
      next.erase(v);
      v = w;
    }
    if (loop.size() < 3) continue;
    Vec3f centroid(0, 0, 0);
    for (int i : loop) centroid += mesh.positions[i];
    const int c = int(mesh.positions.size());
    mesh.positions.push_back(centroid / float(loop.size()));
    if (mesh.has_colors()) mesh.colors.push_back(mesh.colors[loop[0]]);
    for (size_t i = 0; i < loop.size(); ++i) mesh.faces.push_back({loop[(i + 1) % loop.size()], loop[i], c});
    ++filled;
  }
  return filled;
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
    report.holes_filled += fill_boundary_loops(mesh);
    if (mesh_topology(mesh).closed_manifold()) {
      report.closed_manifold = true;
      break;
    }
  }
  // OrientTriangles may have turned everything inside out.
  if (mesh_topology(mesh).volume < 0)
    for (Vec3i& f : mesh.faces) std::swap(f[1], f[2]);
  return report;
}

}  // namespace u3d
