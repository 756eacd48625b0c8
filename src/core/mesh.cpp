#include "core/mesh.h"

#include <Eigen/Geometry>  // cross()
#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace u3d {

bool Mesh::has_texture() const {
  for (const auto& m : materials)
    if (!m.texture.empty()) return has_uvs();
  return false;
}

void Mesh::validate(const std::string& what) const {
  // Per-element checks build their message only on failure: building it eagerly costs more than
  // the check itself on million-face meshes.
  require(!positions.empty(), what + ": mesh has no vertices");
  require(!faces.empty(), what + ": mesh has no faces");
  for (size_t i = 0; i < positions.size(); ++i)
    if (!positions[i].allFinite()) throw Error(what + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
  const int n = int(positions.size());
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      if (faces[f][k] < 0 || faces[f][k] >= n)
        throw Error(what + ": face " + std::to_string(f) + " references vertex " + std::to_string(faces[f][k]) +
                    " but the mesh has " + std::to_string(n) + " vertices");
  require(colors.empty() || colors.size() == positions.size(), what + ": colour count does not match vertex count");
  require(uvs.empty() || uvs.size() == positions.size(), what + ": UV count does not match vertex count");
  require(face_material.empty() || face_material.size() == faces.size(), what + ": material index count does not match face count");
  for (int m : face_material)
    if (!(m >= 0 && (m < int(materials.size()) || (materials.empty() && m == 0))))
      throw Error(what + ": face material index out of range");
  for (const auto& c : colors)
    if (!c.allFinite()) throw Error(what + ": vertex colour is NaN");
  for (const auto& t : uvs)
    if (!t.allFinite()) throw Error(what + ": UV is NaN");
}

BoundingBox bounding_box(const std::vector<Vec3f>& positions) {
  BoundingBox b;
  if (positions.empty()) return b;
  b.min = b.max = positions[0];
  for (const auto& p : positions) {
    b.min = b.min.cwiseMin(p);
    b.max = b.max.cwiseMax(p);
  }
  return b;
}

std::vector<Vec3f> face_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces) {
  std::vector<Vec3f> out(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    const Vec3f& a = positions[faces[f][0]];
    Vec3f n = (positions[faces[f][1]] - a).cross(positions[faces[f][2]] - a);
    float len = n.norm();
    out[f] = len > 0 ? Vec3f(n / len) : Vec3f::Zero();
  }
  return out;
}

std::vector<Vec3f> vertex_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces) {
  std::vector<Vec3f> acc(positions.size(), Vec3f::Zero());
  for (const auto& f : faces) {
    const Vec3f& a = positions[f[0]];
    Vec3f n = (positions[f[1]] - a).cross(positions[f[2]] - a);  // length = 2 * area: area weighting
    for (int k = 0; k < 3; ++k) acc[f[k]] += n;
  }
  for (auto& n : acc) {
    float len = n.norm();
    n = len > 0 ? Vec3f(n / len) : Vec3f::Zero();
  }
  return acc;
}

Similarity normalize_to_unit_box(Mesh& mesh, float fill) {
  require(fill > 0, "fill must be positive");
  BoundingBox b = bounding_box(mesh.positions);
  // Near the float limit the extent and the centre overflow: such a mesh is too large, not flat.
  const float reach = std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff());
  require(reach <= 1e30f, "cannot normalize a mesh with coordinates beyond 1e30 (it reaches " +
                              std::to_string(double(reach)) + ")");
  const float longest = b.extent().maxCoeff();
  require(longest > 0, "cannot normalize a mesh with zero size");
  Similarity s;
  s.offset = -b.center();
  s.scale = 2.f * fill / longest;
  for (auto& p : mesh.positions) p = s.scale * (p + s.offset);
  return s;
}

}  // namespace u3d
