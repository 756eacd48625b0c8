#pragma once
// Pillow's Image.resize for 8-bit images, reproduced bit for bit: separable convolution with Pillow's
// filter kernels and support scaling, coefficients in 22-bit fixed point, horizontal pass first, each
// pass rounded and clipped to uint8. The diffusion models' preprocessing (CLIPImageProcessor: bicubic;
// VaeImageProcessor: Lanczos) was done with it, so matching it makes the inputs identical.
#include <torch/torch.h>

#include "core/image.h"

namespace u3d::nn {

enum class PilFilter { Bilinear, Bicubic, Lanczos };

// Pillow's numbering (Image.Resampling): 1 Lanczos, 2 bilinear, 3 bicubic. Error for the others.
PilFilter pil_filter_from_code(int code);

// image: uint8 [H, W, C] (any channel count; channels are independent). Returns uint8 [out_h, out_w, C].
torch::Tensor pil_resize(const torch::Tensor& image, int64_t out_width, int64_t out_height, PilFilter filter);

// Image (float [0, 1], RGB or RGBA) -> uint8 [H, W, 3] RGB, rounding to nearest; alpha is dropped as
// PIL's convert("RGB") does.
torch::Tensor image_to_uint8_rgb(const Image& image);

}  // namespace u3d::nn
