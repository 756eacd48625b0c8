#include "geometry/open3d_bridge.h"

#include <open3d/geometry/TriangleMesh.h>

namespace u3d {

std::shared_ptr<open3d::geometry::TriangleMesh> to_open3d(const Mesh& mesh) {
  auto out = std::make_shared<open3d::geometry::TriangleMesh>();
  out->vertices_.reserve(mesh.positions.size());
  for (const Vec3f& p : mesh.positions) out->vertices_.push_back(p.cast<double>());
  out->triangles_.reserve(mesh.faces.size());
  for (const Vec3i& f : mesh.faces) out->triangles_.push_back(f);
  for (const Vec3f& c : mesh.colors) out->vertex_colors_.push_back(c.cast<double>());
  return out;
}

Mesh from_open3d(const open3d::geometry::TriangleMesh& mesh) {
  Mesh out;
  out.positions.reserve(mesh.vertices_.size());
  for (const Eigen::Vector3d& p : mesh.vertices_) out.positions.push_back(p.cast<float>());
  out.faces.reserve(mesh.triangles_.size());
  for (const Eigen::Vector3i& f : mesh.triangles_) out.faces.push_back(f);
  if (mesh.vertex_colors_.size() == mesh.vertices_.size())
    for (const Eigen::Vector3d& c : mesh.vertex_colors_) out.colors.push_back(c.cast<float>());
  return out;
}

}  // namespace u3d
