#include "nn/checkpoint/diffusers_folder.h"

#include <vector>

#include "core/error.h"
#include "nn/checkpoint/pth_reader.h"
#include "nn/checkpoint/safetensors.h"

namespace fs = std::filesystem;

namespace u3d::nn {

std::string DiffusersFolder::default_download_hint() {
  return "the Unique3D checkpoints are the ckpt/ folder of the Hugging Face space Wuvin/Unique3D "
         "(ckpt/img2mvimg, ckpt/image2normal); the plain image-variation model is "
         "lambdalabs/sd-image-variations-diffusers";
}

DiffusersFolder::DiffusersFolder(fs::path root, std::string download_hint)
    : root_(std::move(root)), download_hint_(std::move(download_hint)) {
  require(fs::is_directory(root_), "model folder " + root_.string() + " does not exist or is not a folder; " +
                                       download_hint_);
}

void DiffusersFolder::missing(const std::string& what) const {
  throw Error("model folder " + root_.string() + " is incomplete: " + what + " is missing; " + download_hint_);
}

fs::path DiffusersFolder::file(const fs::path& relative) const {
  const fs::path path = root_ / relative;
  if (!fs::is_regular_file(path)) missing(path.string());
  return path;
}

fs::path DiffusersFolder::component_config(const std::string& component) const {
  return file(fs::path(component) / "config.json");
}

fs::path DiffusersFolder::component_weights(const std::string& component) const {
  // transformers models (image_encoder) use model.* / pytorch_model.bin, diffusers models diffusion_pytorch_model.*.
  const std::vector<std::string> names = {"diffusion_pytorch_model.safetensors", "model.safetensors",
                                          "diffusion_pytorch_model.bin", "pytorch_model.bin"};
  for (const auto& name : names) {
    const fs::path path = root_ / component / name;
    if (fs::is_regular_file(path)) return path;
  }
  missing((root_ / component).string() + "/{diffusion_pytorch_model,model}.safetensors (or the .bin variant)");
}

fs::path DiffusersFolder::preprocessor_config() const {
  return file(fs::path("feature_extractor") / "preprocessor_config.json");
}

fs::path DiffusersFolder::scheduler_config() const { return file(fs::path("scheduler") / "scheduler_config.json"); }

TensorMap load_weights_file(const fs::path& path) {
  return path.extension() == ".safetensors" ? load_safetensors(path) : load_pth(path);
}

}  // namespace u3d::nn
