#include "render/shade.h"

#include <Eigen/Geometry>

#include "core/error.h"
#include "render/texture_sampler.h"

namespace u3d {

namespace {

// Shading loops are cheap per pixel; a team of threads only pays off on big images.
constexpr size_t kMinParallelPixels = 256 * 256;

Vec3f interpolate(const std::vector<Vec3f>& values, const Vec3i& face, const Vec2f& b) {
  return (1.f - b.x() - b.y()) * values[face[0]] + b.x() * values[face[1]] + b.y() * values[face[2]];
}

void write_normal(float* px, const Vec3f& n) {
  px[0] = 0.5f * (n.x() + 1.f);
  px[1] = 0.5f * (n.y() + 1.f);
  px[2] = 0.5f * (n.z() + 1.f);
  px[3] = 1.f;
}

// Calls shade(pixel index, output pixel) for every covered pixel of a new RGBA image.
template <typename Shade>
Image shade_covered(const RasterBuffer& buf, Shade&& shade) {
  Image out(buf.width, buf.height, 4, 0.f);
  const int64_t n = int64_t(buf.pixel_count());
#pragma omp parallel for schedule(static) if (size_t(n) >= kMinParallelPixels)
  for (int64_t i = 0; i < n; ++i)
    if (buf.face_id[i] >= 0) shade(size_t(i), out.data.data() + size_t(i) * 4);
  return out;
}

}  // namespace

Image shade_vertex_normals(const RasterBuffer& buf, const std::vector<Vec3f>& positions,
                           const std::vector<Vec3i>& faces, const std::vector<Vec3f>& vertex_normals,
                           const Camera& camera, NormalSpace space) {
  require(vertex_normals.size() == positions.size(), "shade_vertex_normals: one normal per vertex expected");
  const Eigen::Matrix3f rot = space == NormalSpace::Camera ? camera.rotation() : Eigen::Matrix3f::Identity();
  return shade_covered(buf, [&](size_t i, float* px) {
    const Vec3i& f = faces[buf.face_id[i]];
    Vec3f n = interpolate(vertex_normals, f, buf.bary[i]);
    float len = n.norm();
    if (len > 1e-12f) {
      n /= len;
    } else {
      n = (positions[f[1]] - positions[f[0]]).cross(positions[f[2]] - positions[f[0]]).normalized();
    }
    write_normal(px, rot * n);
  });
}

Image shade_face_normals(const RasterBuffer& buf, const std::vector<Vec3f>& face_normals, const Camera& camera,
                         NormalSpace space) {
  const Eigen::Matrix3f rot = space == NormalSpace::Camera ? camera.rotation() : Eigen::Matrix3f::Identity();
  return shade_covered(buf, [&](size_t i, float* px) { write_normal(px, rot * face_normals[buf.face_id[i]]); });
}

bool has_color_information(const Mesh& mesh) {
  if (mesh.has_colors() || mesh.has_texture()) return true;
  for (const auto& m : mesh.materials)
    if (m.base_color.head<3>() != Vec3f::Ones()) return true;
  return false;
}

Image shade_colors(const RasterBuffer& buf, const Mesh& mesh) {
  if (!has_color_information(mesh)) return shade_covered(buf, [](size_t, float* px) {
      px[0] = px[1] = px[2] = 0.5f;
      px[3] = 1.f;
    });
  const Material default_material;
  const bool uvs = mesh.has_uvs();
  return shade_covered(buf, [&](size_t i, float* px) {
    const int face = buf.face_id[i];
    const Vec3i& f = mesh.faces[face];
    const int m = mesh.material_of(face);
    const Material& mat = m < int(mesh.materials.size()) ? mesh.materials[m] : default_material;
    Vec3f c = mat.base_color.head<3>();
    if (mesh.has_colors()) c = c.cwiseProduct(interpolate(mesh.colors, f, buf.bary[i]));
    if (uvs && !mat.texture.empty()) {
      const Vec2f& b = buf.bary[i];
      Vec2f uv = (1.f - b.x() - b.y()) * mesh.uvs[f[0]] + b.x() * mesh.uvs[f[1]] + b.y() * mesh.uvs[f[2]];
      c = c.cwiseProduct(sample_texture(mat.texture, uv).head<3>());
    }
    px[0] = c.x();
    px[1] = c.y();
    px[2] = c.z();
    px[3] = 1.f;
  });
}

}  // namespace u3d
