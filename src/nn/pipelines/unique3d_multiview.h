#pragma once
// Unique3D's image-to-four-views stage, loaded from the official checkpoint folder ckpt/img2mvimg (a
// diffusers folder of sd-image-variations plus unet_state_dict.pth, see nn/checkpoint/diffusers_folder.h)
// and run as the official app runs it (app/custom_models/mvimg_prediction.py with image2mvimage.yaml):
// the UNet of unet/config.json with 8 input channels (the condition latents are concatenated) and 8
// class embeddings, its weights from unet_state_dict.pth; joint attention over the 4 views on every
// attn1; class labels 0..3; EulerAncestral built from scheduler/scheduler_config.json; CLIP and VAE from
// their sub-folders. Defaults are the app's: 256 px views and condition, 30 steps, guidance 1.5.
#include <torch/torch.h>

#include <filesystem>
#include <memory>
#include <vector>

#include "nn/checkpoint/checkpoint_reader.h"
#include "nn/checkpoint/tensor_map.h"
#include "nn/models/unet.h"
#include "nn/pipelines/image_diffusion.h"
#include "nn/precision.h"
#include "nn/schedulers/noise_source.h"

namespace u3d::nn {

struct MultiViewSettings {
  int64_t size = 256;  // side of each view and of the encoded condition
  int steps = 30;
  double guidance_scale = 1.5;
  // Free each network as soon as this run no longer needs it (docs/networks.md, "Memory"): the model
  // cannot run again afterwards. The pipeline stages run each model once and set it.
  bool free_networks_as_done = false;
};

class MultiViewModel {
 public:
  // Checks that every file the stage needs is there (an Error names the first missing one and where the
  // folder comes from) before reading any weights, then loads and converts to `precision`. With a checking
  // `reader` the model is built on the meta device, only to check the checkpoints.
  static std::unique_ptr<MultiViewModel> load(const std::filesystem::path& folder, Precision precision,
                                              const CheckpointReader& reader = {});
  // The files load() reads, checked to exist (an Error names the first missing one); reads nothing.
  static std::vector<std::filesystem::path> files(const std::filesystem::path& folder);

  // condition: uint8 RGB [H, W, 3], the object on white as the official app passes it. Returns float
  // [4, size, size, 3] in [0, 1], the model's four views in its own order (class labels 0..3). The initial
  // latents and the per-step noise come from `noise`; `trace` as in run_image_diffusion.
  torch::Tensor run(const torch::Tensor& condition, const MultiViewSettings& settings, NoiseSource& noise,
                    TensorMap* trace = nullptr);

  ConditioningModels parts;  // CLIP, feature extractor, VAE, scheduler of the same folder
  UNet2DConditionModel unet{nullptr};
};

}  // namespace u3d::nn
