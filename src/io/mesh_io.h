#pragma once
// Mesh files. Reading: .obj (+ .mtl, several materials and textures), .ply, .glb/.gltf (tinygltf,
// node transforms applied). Writing: .glb (vertex colours as linear COLOR_0, textures as sRGB PNG),
// .obj (+ .mtl + textures), .ply. The format is chosen by extension; writes are atomic.
// Errors (missing file, corrupt content, empty mesh, NaN) are u3d::Error naming the file.
#include <filesystem>

#include "core/mesh.h"
#include "io/image_codec.h"

namespace u3d {

struct MeshWriteOptions {
  TextureFormat texture_format = TextureFormat::Png;  // textures embedded in a GLB or written beside the file
};

Mesh read_mesh(const std::filesystem::path& path);
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, const MeshWriteOptions& options = {});

}  // namespace u3d
