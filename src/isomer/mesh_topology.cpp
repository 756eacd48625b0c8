#include "isomer/mesh_topology.h"

#include <open3d/geometry/TriangleMesh.h>

#include <cstdio>

#include "isomer/open3d_bridge.h"

namespace u3d {

std::string MeshTopology::summary() const {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s, %s, %d component(s), Euler characteristic %d, volume %.4f",
                watertight ? "closed" : "open", edge_manifold && vertex_manifold ? "manifold" : "non-manifold",
                components, euler_characteristic, volume);
  return buf;
}

MeshTopology mesh_topology(const Mesh& mesh) {
  MeshTopology t;
  auto o3d = to_open3d(mesh);
  t.edge_manifold = o3d->IsEdgeManifold(true);
  t.vertex_manifold = o3d->IsVertexManifold();
  // Open3D's IsWatertight also tests self-intersection (quadratic in the face count); closed here
  // means what ISOMER needs: no boundary edge.
  t.watertight = o3d->GetNonManifoldEdges(false).empty();
  t.components = int(std::get<1>(o3d->ClusterConnectedTriangles()).size());
  t.euler_characteristic = o3d->EulerPoincareCharacteristic();
  // Divergence theorem; valid for any closed surface, meaningful as an orientation check.
  for (const Vec3i& f : mesh.faces)
    t.volume += mesh.positions[f[0]].cast<double>().dot(
                    mesh.positions[f[1]].cast<double>().cross(mesh.positions[f[2]].cast<double>())) /
                6.0;
  return t;
}

}  // namespace u3d
