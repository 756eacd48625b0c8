#include "eval/mesh_checks.h"

#include <Eigen/Geometry>

#include <functional>
#include <unordered_map>

#include "geometry/edge_topology.h"

namespace u3d {

namespace {

// Vertices at the same position count as one: files split vertices along UV and colour seams, which
// must not look like holes.
std::vector<uint32_t> weld_by_position(const std::vector<Vec3f>& positions) {
  struct Hash {
    size_t operator()(const Vec3f& p) const {
      return std::hash<float>()(p.x()) ^ (std::hash<float>()(p.y()) * 31) ^ (std::hash<float>()(p.z()) * 961);
    }
  };
  std::unordered_map<Vec3f, uint32_t, Hash> first_index;
  first_index.reserve(positions.size());
  std::vector<uint32_t> canonical(positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    canonical[i] = first_index.emplace(positions[i], uint32_t(i)).first->second;
  return canonical;
}

}  // namespace

MeshDiagnostics diagnose_mesh(const Mesh& mesh) {
  MeshDiagnostics d;
  const std::vector<uint32_t> id = weld_by_position(mesh.positions);
  std::vector<Vec3i> welded;  // the faces that are not degenerate, on the welded vertices
  welded.reserve(mesh.faces.size());
  for (const auto& f : mesh.faces) {
    const Vec3f& a = mesh.positions[f[0]];
    if (id[f[0]] == id[f[1]] || id[f[1]] == id[f[2]] || id[f[2]] == id[f[0]] ||
        (mesh.positions[f[1]] - a).cross(mesh.positions[f[2]] - a).squaredNorm() == 0.f) {
      ++d.degenerate_faces;
      continue;
    }
    welded.push_back(Vec3i(int(id[f[0]]), int(id[f[1]]), int(id[f[2]])));
  }
  const EdgeSideLists edges = edge_side_lists(build_edge_topology(welded, mesh.vertex_count()));
  for (size_t e = 0; e < edges.edge_count(); ++e) {
    const int uses = edges.count(int(e));
    if (uses == 1) ++d.boundary_edges;
    if (uses >= 3) ++d.nonmanifold_edges;
  }
  return d;
}

std::vector<std::string> mesh_warnings(const MeshDiagnostics& d, const std::string& what) {
  std::vector<std::string> out;
  if (d.boundary_edges > 0)
    out.push_back(what + " is not closed (" + std::to_string(d.boundary_edges) +
                  " boundary edges): its inside is estimated by winding numbers and is approximate near holes");
  if (d.nonmanifold_edges > 0)
    out.push_back(what + " has " + std::to_string(d.nonmanifold_edges) + " non-manifold edges");
  if (d.degenerate_faces > 0)
    out.push_back(what + " has " + std::to_string(d.degenerate_faces) + " degenerate (zero-area) faces");
  return out;
}

}  // namespace u3d
