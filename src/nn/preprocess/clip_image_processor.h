#pragma once
// transformers CLIPImageProcessor (as configured by preprocessor_config.json): resize the shortest edge
// with Pillow's filter on uint8 (bit-exact, see pil_resize.h), centre crop, rescale by 1/255, normalise
// with the CLIP mean/std, HWC -> CHW.
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <torch/torch.h>

#include "nn/preprocess/pil_resize.h"

namespace u3d::nn {

struct ClipImageProcessorConfig {
  bool do_resize = true;
  int64_t shortest_edge = 224;
  PilFilter resample = PilFilter::Bicubic;
  bool do_center_crop = true;
  int64_t crop_height = 224, crop_width = 224;
  bool do_rescale = true;
  double rescale_factor = 1.0 / 255.0;
  bool do_normalize = true;
  std::array<float, 3> image_mean{0.48145466f, 0.4578275f, 0.40821073f};
  std::array<float, 3> image_std{0.26862954f, 0.26130258f, 0.27577711f};

  static ClipImageProcessorConfig from_json(const nlohmann::json& json, const std::string& source);
};

class ClipImageProcessor {
 public:
  explicit ClipImageProcessor(ClipImageProcessorConfig config);

  // uint8 RGB [H, W, 3] -> the resized and centre-cropped uint8 image [crop_h, crop_w, 3].
  torch::Tensor resize_and_crop(const torch::Tensor& rgb) const;
  // uint8 RGB [H, W, 3] -> float32 pixel_values [1, 3, crop_h, crop_w].
  torch::Tensor pixel_values(const torch::Tensor& rgb) const;

  const ClipImageProcessorConfig& config() const { return config_; }

 private:
  ClipImageProcessorConfig config_;
};

}  // namespace u3d::nn
