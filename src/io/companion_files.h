#pragma once
// Formats that spread one mesh over several files (OBJ + MTL + textures, PLY + texture) write every
// file atomically and remove the ones already written when a later one fails, so a failed write
// leaves no partial set behind.
#include <filesystem>
#include <functional>
#include <vector>

#include "core/image.h"
#include "io/image_codec.h"

namespace u3d {

class CompanionFiles {
 public:
  CompanionFiles() = default;
  CompanionFiles(const CompanionFiles&) = delete;
  CompanionFiles& operator=(const CompanionFiles&) = delete;
  ~CompanionFiles();  // removes everything written unless commit() was called

  void write(const std::filesystem::path& path, const std::function<void(const std::filesystem::path& tmp)>& writer);
  void write_image(const Image& image, const std::filesystem::path& path);  // PNG or JPEG by extension
  void commit() { written_.clear(); }

 private:
  std::vector<std::filesystem::path> written_;
};

// Name of the texture file of material `index` next to a mesh file: model_texture.png (or .jpg), or
// model_texture0.png, model_texture1.png, ... when several materials have textures.
std::filesystem::path texture_path_for(const std::filesystem::path& mesh_path, int index, bool several,
                                       TextureFormat format = TextureFormat::Png);

}  // namespace u3d
