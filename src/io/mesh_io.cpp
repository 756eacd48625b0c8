// Format dispatch by file extension; every mesh read is validated, every mesh written is validated first.
#include "io/mesh_io.h"

#include <algorithm>

#include "core/error.h"
#include "io/mesh_formats.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

std::string lowercase_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

}  // namespace

Mesh read_mesh(const fs::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  require(fs::exists(path, ec), "mesh file not found: " + file);
  require(fs::is_regular_file(path, ec), "expected a mesh file, got a folder or device: " + file);
  std::string ext = lowercase_extension(path);
  require(ext == ".obj" || ext == ".ply" || ext == ".glb" || ext == ".gltf",
          "unsupported mesh file extension '" + ext + "' (use .obj, .ply, .glb or .gltf): " + file);
  Mesh mesh = ext == ".obj" ? read_obj(path) : ext == ".ply" ? read_ply(path) : read_gltf(path);
  mesh.validate(file);
  return mesh;
}

void write_mesh(const Mesh& mesh, const fs::path& path, const MeshWriteOptions& options) {
  const std::string file = path.string();
  std::string ext = lowercase_extension(path);
  require(ext == ".obj" || ext == ".ply" || ext == ".glb",
          "unsupported output mesh extension '" + ext + "' (use .glb, .obj or .ply): " + file);
  mesh.validate("cannot write " + file);
  if (ext == ".glb") write_glb(mesh, path, options.texture_format);
  else if (ext == ".obj") write_obj(mesh, path, options.texture_format);
  else write_ply(mesh, path, options.texture_format);
}

}  // namespace u3d
