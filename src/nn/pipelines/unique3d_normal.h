#pragma once
// Unique3D's normal-map stage, loaded as the official app loads it (app/custom_models/normal_prediction.py
// with image2normal.yaml): the sd-image-variations diffusers folder gives the UNet config, CLIP, VAE,
// feature extractor and scheduler; ckpt/image2normal/unet_state_dict.pth gives the main UNet with its
// crosspond_attention weights and, when it holds them, the reference UNet under "ref_unet." (else the
// reference is the folder's plain UNet). Run on a batch of views, each its own condition, with the
// reference attention (nn/models/unet_reference.h). Defaults are the app's: 512 px, 30 steps, guidance
// 2.0. The official post-processing (background removal, rotating each view's normals to world space)
// is not part of this stage.
#include <torch/torch.h>

#include <filesystem>
#include <memory>
#include <vector>

#include "nn/checkpoint/checkpoint_reader.h"
#include "nn/checkpoint/tensor_map.h"
#include "nn/models/unet_reference.h"
#include "nn/pipelines/image_diffusion.h"
#include "nn/precision.h"
#include "nn/schedulers/noise_source.h"

namespace u3d::nn {

struct NormalSettings {
  int64_t size = 512;  // side of each normal map and of the encoded condition
  int steps = 30;
  double guidance_scale = 2.0;
  // Free each network as soon as this run no longer needs it (docs/networks.md, "Memory"): the model
  // cannot run again afterwards. The pipeline stages run each model once and set it.
  bool free_networks_as_done = false;
};

class NormalModel {
 public:
  // image_variations: the sd-image-variations diffusers folder; image2normal: the official
  // ckpt/image2normal folder. Every file is checked before any weights are read. With a checking `reader`
  // the model is built on the meta device, only to check the checkpoints.
  static std::unique_ptr<NormalModel> load(const std::filesystem::path& image_variations,
                                           const std::filesystem::path& image2normal, Precision precision,
                                           const CheckpointReader& reader = {});
  // As load() without the UNets, which load_unet() reads later: a run that encodes its views first
  // (encode() with free_networks_as_done) never holds the CLIP image encoder, the encoding's activations
  // and the UNets' weights (6.6 GB of the model's 8 GB in fp32) at once.
  static std::unique_ptr<NormalModel> load_conditioning(const std::filesystem::path& image_variations,
                                                        const std::filesystem::path& image2normal, Precision precision);
  // Reads the UNets when `unet` is empty.
  void load_unet();
  // The files load() reads, checked to exist (an Error names the first missing one); reads nothing.
  static std::vector<std::filesystem::path> files(const std::filesystem::path& image_variations,
                                                  const std::filesystem::path& image2normal);

  // views: uint8 RGB [H, W, 3] each (the official app passes the views on white). Returns float
  // [views, size, size, 3] in [0, 1]: each view's normal map in camera space as the model draws it.
  // encode() then sample(), loading the UNets in between when they are not loaded.
  torch::Tensor run(const std::vector<torch::Tensor>& views, const NormalSettings& settings, NoiseSource& noise,
                    TensorMap* trace = nullptr);
  // run()'s two halves (nn/pipelines/image_diffusion.h); sample() needs the UNets.
  ImageConditions encode(const std::vector<torch::Tensor>& views, const NormalSettings& settings,
                         TensorMap* trace = nullptr);
  torch::Tensor sample(const ImageConditions& conditions, const NormalSettings& settings, NoiseSource& noise,
                       TensorMap* trace = nullptr);

  ConditioningModels parts;
  std::unique_ptr<ReferenceUNet> unet;

 private:
  ImageDiffusionModels models();
  std::filesystem::path image_variations_, image2normal_;
  Precision precision_ = Precision::kFp32;
};

}  // namespace u3d::nn
