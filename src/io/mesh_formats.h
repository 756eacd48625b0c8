#pragma once
// One reader/writer per file format; mesh_io.cpp picks one by extension and validates the result.
// Readers throw Error naming the file for content they cannot parse.
#include <filesystem>

#include "core/mesh.h"
#include "io/image_codec.h"

namespace u3d {

Mesh read_obj(const std::filesystem::path& path);
Mesh read_ply(const std::filesystem::path& path);
Mesh read_gltf(const std::filesystem::path& path);  // .glb and .gltf

// Textures go out as `texture_format` (PNG or JPEG), embedded (GLB) or as files beside the mesh.
void write_obj(const Mesh& mesh, const std::filesystem::path& path, TextureFormat texture_format = TextureFormat::Png);
void write_ply(const Mesh& mesh, const std::filesystem::path& path, TextureFormat texture_format = TextureFormat::Png);
void write_glb(const Mesh& mesh, const std::filesystem::path& path, TextureFormat texture_format = TextureFormat::Png);

}  // namespace u3d
