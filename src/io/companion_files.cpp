#include "io/companion_files.h"

#include "core/atomic_file.h"

namespace u3d {

namespace fs = std::filesystem;

CompanionFiles::~CompanionFiles() {
  std::error_code ec;
  for (const auto& path : written_) fs::remove(path, ec);
}

void CompanionFiles::write(const fs::path& path, const std::function<void(const fs::path& tmp)>& writer) {
  write_atomically(path, writer);
  written_.push_back(path);
}

void CompanionFiles::write_image(const Image& image, const fs::path& path) {
  save_image(image, path);
  written_.push_back(path);
}

fs::path texture_path_for(const fs::path& mesh_path, int index, bool several, TextureFormat format) {
  std::string name =
      mesh_path.stem().string() + "_texture" + (several ? std::to_string(index) : "") + texture_extension(format);
  return mesh_path.parent_path() / name;
}

}  // namespace u3d
