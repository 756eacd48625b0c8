#pragma once
// The on-disk layout of a diffusers model folder, as published on Hugging Face (e.g.
// lambdalabs/sd-image-variations-diffusers, or the Unique3D space Wuvin/Unique3D's ckpt/img2mvimg and
// ckpt/image2normal, which add unet_state_dict.pth):
//
//   unet/config.json           unet/diffusion_pytorch_model.safetensors   (or .bin)
//   vae/config.json            vae/diffusion_pytorch_model.safetensors    (or .bin)
//   image_encoder/config.json  image_encoder/model.safetensors            (or pytorch_model.bin)
//   feature_extractor/preprocessor_config.json
//   scheduler/scheduler_config.json
//
// Every accessor returns an existing file or throws a u3d::Error naming the missing file and where
// to download it.
#include <filesystem>
#include <string>

#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

class DiffusersFolder {
 public:
  // `download_hint` says where the folder comes from, for error messages; the default names the
  // Unique3D checkpoints and the sd-image-variations model.
  explicit DiffusersFolder(std::filesystem::path root, std::string download_hint = default_download_hint());

  const std::filesystem::path& root() const { return root_; }

  // <root>/<component>/config.json, e.g. component "unet", "vae", "image_encoder".
  std::filesystem::path component_config(const std::string& component) const;
  // The component's weights: *.safetensors preferred over the torch *.bin.
  std::filesystem::path component_weights(const std::string& component) const;
  std::filesystem::path preprocessor_config() const;
  std::filesystem::path scheduler_config() const;
  // Any other file of the folder, e.g. "unet_state_dict.pth".
  std::filesystem::path file(const std::filesystem::path& relative) const;

  static std::string default_download_hint();

 private:
  [[noreturn]] void missing(const std::string& what) const;

  std::filesystem::path root_;
  std::string download_hint_;
};

// Reads a weights file by its extension: .safetensors, else the torch zip format (.pth, .bin).
TensorMap load_weights_file(const std::filesystem::path& path);

}  // namespace u3d::nn
