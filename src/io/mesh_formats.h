#pragma once
// One reader/writer per file format; mesh_io.cpp picks one by extension and validates the result.
// Readers throw Error naming the file for content they cannot parse.
#include <filesystem>

#include "core/mesh.h"

namespace u3d {

Mesh read_obj(const std::filesystem::path& path);
Mesh read_ply(const std::filesystem::path& path);
Mesh read_gltf(const std::filesystem::path& path);  // .glb and .gltf

void write_obj(const Mesh& mesh, const std::filesystem::path& path);
void write_ply(const Mesh& mesh, const std::filesystem::path& path);
void write_glb(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace u3d
