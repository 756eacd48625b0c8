// Binary little-endian PLY writer: float positions, uchar colours, float s/t UVs and int triangle
// lists. PLY has no materials: the first material's texture is written next to it as a PNG (or JPEG) and named
// in a "comment TextureFile" line (MeshLab's convention).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>

#include "core/error.h"
#include "io/companion_files.h"
#include "io/mesh_formats.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

static_assert(std::endian::native == std::endian::little, "the PLY writer stores native little-endian values");

template <typename T>
void append_binary(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

uint8_t to_byte(float c) { return uint8_t(std::lround(std::clamp(c, 0.f, 1.f) * 255.f)); }

std::string ply_bytes(const Mesh& mesh, const fs::path& texture) {
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by unique3d\n";
  if (!texture.empty()) out += "comment TextureFile " + texture.filename().string() + "\n";
  out += "element vertex " + std::to_string(mesh.vertex_count()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (mesh.has_colors()) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (mesh.has_uvs()) out += "property float s\nproperty float t\n";
  out += "element face " + std::to_string(mesh.face_count()) + "\n";
  out += "property list uchar int vertex_indices\nend_header\n";
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    for (int c = 0; c < 3; ++c) append_binary(out, mesh.positions[v][c]);
    if (mesh.has_colors())
      for (int c = 0; c < 3; ++c) append_binary(out, to_byte(mesh.colors[v][c]));
    if (mesh.has_uvs())
      for (int c = 0; c < 2; ++c) append_binary(out, mesh.uvs[v][c]);
  }
  for (const Vec3i& f : mesh.faces) {
    append_binary(out, uint8_t(3));
    for (int k = 0; k < 3; ++k) append_binary(out, int32_t(f[k]));
  }
  return out;
}

}  // namespace

void write_ply(const Mesh& mesh, const fs::path& path, TextureFormat texture_format) {
  const Material* textured = nullptr;
  if (mesh.has_uvs())
    for (const auto& m : mesh.materials)
      if (!m.texture.empty()) {
        textured = &m;
        break;
      }
  fs::path texture = textured ? texture_path_for(path, 0, false, texture_format) : fs::path();

  CompanionFiles files;
  if (textured) files.write_image(textured->texture, texture);
  files.write(path, [&](const fs::path& tmp) {
    std::string bytes = ply_bytes(mesh, texture);
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.close();
    require(out.good(), "cannot write " + path.string());
  });
  files.commit();
}

}  // namespace u3d
