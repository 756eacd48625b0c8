#pragma once
// Wavefront material libraries (.mtl): diffuse colour Kd, opacity d/Tr and diffuse texture map_Kd.
#include <filesystem>
#include <map>
#include <string>

#include "core/mesh.h"

namespace u3d {

struct MtlEntry {
  Material material;                   // name, base colour; texture not loaded yet
  std::filesystem::path texture_path;  // map_Kd resolved against the .mtl folder; empty = none
};

// Throws Error naming the file if it is missing or a value cannot be parsed.
std::map<std::string, MtlEntry> read_mtl(const std::filesystem::path& path);

}  // namespace u3d
