#pragma once
// The folder of network weights that `--models` names: the official release's ckpt/ folder (Hugging
// Face space Wuvin/Unique3D, ckpt/), in its own layout, plus the public models the official code
// downloads at run time, each under the folder name its publisher uses. Paths only: each stage's
// loader checks its own files and names the missing one with where to get it (docs/models.md lists
// every file with its size and source).
#include <filesystem>
#include <string>
#include <vector>

namespace u3d {

class ModelFolder {
 public:
  // Error when `root` is not an existing folder.
  explicit ModelFolder(std::filesystem::path root);

  const std::filesystem::path& root() const { return root_; }

  // ckpt/img2mvimg: a diffusers folder of sd-image-variations with Unique3D's unet_state_dict.pth.
  std::filesystem::path img2mvimg() const { return root_ / "img2mvimg"; }
  // ckpt/image2normal, which holds unet_state_dict.pth.
  std::filesystem::path image2normal() const { return root_ / "image2normal"; }
  // The sd-image-variations diffusers folder the normal model is built on: image2normal/ itself when it
  // is a whole diffusers folder (as the official ckpt/image2normal is), else
  // sd-image-variations-diffusers/ (lambdalabs/sd-image-variations-diffusers).
  std::filesystem::path image_variations_for_normals() const;
  // The refinement's models: runwayml/stable-diffusion-v1-5 (diffusers layout), the release's
  // controlnet-tile/, and the h94/IP-Adapter repository (models/ip-adapter_sd15.safetensors,
  // models/image_encoder/).
  std::filesystem::path stable_diffusion() const { return root_ / "stable-diffusion-v1-5"; }
  std::filesystem::path ip_adapter() const { return root_ / "IP-Adapter"; }
  // Real-ESRGAN x4: the release's realesrgan-x4.onnx, else basicsr's RealESRGAN_x4plus.pth. Error when
  // neither is there.
  std::filesystem::path upscaler() const;
  // Background removal: rembg's u2net.onnx (what the official app uses), else rembg's
  // isnet-general-use.onnx, else imgly's isnet_medium_fp16.onnx. Error when none is there.
  std::filesystem::path matting() const;

 private:
  std::filesystem::path first_existing(const std::vector<std::string>& names, const std::string& what,
                                       const std::string& source) const;

  std::filesystem::path root_;
};

}  // namespace u3d
