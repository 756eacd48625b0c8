#pragma once
// Triangle mesh: shared vertices, counter-clockwise faces seen from outside, optional per-vertex
// colours and UVs, and materials (base colour + optional texture). Conventions: docs/conventions.md.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/image.h"

namespace u3d {

using Vec2f = Eigen::Vector2f;
using Vec3f = Eigen::Vector3f;
using Vec4f = Eigen::Vector4f;
using Vec3i = Eigen::Vector3i;

struct Material {
  std::string name;
  Vec4f base_color{1.f, 1.f, 1.f, 1.f};  // sRGB-encoded RGBA, multiplies the texture
  Image texture;                          // sRGB-encoded RGB(A); empty = none
};

struct Mesh {
  std::vector<Vec3f> positions;
  std::vector<Vec3i> faces;
  std::vector<Vec3f> colors;       // per vertex, sRGB-encoded in [0,1]; empty = none
  std::vector<Vec2f> uvs;          // per vertex, OpenGL/OBJ convention: (0,0) = bottom-left of the texture
  std::vector<int> face_material;  // per face, index into materials; empty = material 0 everywhere
  std::vector<Material> materials;

  size_t vertex_count() const { return positions.size(); }
  size_t face_count() const { return faces.size(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_uvs() const { return !uvs.empty(); }
  bool has_texture() const;
  int material_of(size_t face) const { return face_material.empty() ? 0 : face_material[face]; }

  // Throws Error (prefixed with `what`, e.g. the file name) if the mesh is empty, has NaN/Inf
  // positions, out-of-range indices, or attribute arrays whose sizes do not match.
  void validate(const std::string& what = "mesh") const;
};

struct BoundingBox {
  Vec3f min{0, 0, 0};
  Vec3f max{0, 0, 0};
  Vec3f center() const { return 0.5f * (min + max); }
  Vec3f extent() const { return max - min; }
};

BoundingBox bounding_box(const std::vector<Vec3f>& positions);

// Unit face normals (zero for degenerate faces).
std::vector<Vec3f> face_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces);

// Area-weighted unit vertex normals (zero for isolated vertices).
std::vector<Vec3f> vertex_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces);

// Centres the mesh on its bounding-box centre and scales it so its longest side spans
// [-fill, fill]. Returns the applied (scale, offset): p' = scale * (p + offset).
struct Similarity {
  float scale = 1.f;
  Vec3f offset{0, 0, 0};
};
Similarity normalize_to_unit_box(Mesh& mesh, float fill);

}  // namespace u3d
