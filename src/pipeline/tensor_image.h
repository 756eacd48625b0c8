#pragma once
// Conversions between the facade's images (core/image.h: float in [0, 1]) and the tensors the networks
// take and give: 8-bit [H, W, C] as the official code's PIL images, and float [H, W, C] in [0, 1].
// Used inside the pipeline's .cpp files only, so the facade's headers stay free of libtorch.
#include <torch/torch.h>

#include "core/image.h"

namespace u3d {

// uint8 [H, W, C], rounding to nearest; grey becomes RGB, grey+alpha RGBA.
torch::Tensor image_to_uint8(const Image& image);
// uint8 or float [H, W, C] -> Image (uint8 scaled by 1/255, float clamped to [0, 1]).
Image tensor_to_image(const torch::Tensor& hwc);

}  // namespace u3d
