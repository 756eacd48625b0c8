#include "pipeline/model_folder.h"

#include "core/error.h"

namespace u3d {

ModelFolder::ModelFolder(std::filesystem::path root) : root_(std::move(root)) {
  require(std::filesystem::is_directory(root_),
          "model folder " + root_.string() +
              " does not exist: --models names the folder that holds the official checkpoints (the release's "
              "ckpt/ folder, see docs/models.md)");
}

std::filesystem::path ModelFolder::image_variations_for_normals() const {
  if (std::filesystem::exists(image2normal() / "unet" / "config.json")) return image2normal();
  return root_ / "sd-image-variations-diffusers";
}

}  // namespace u3d
