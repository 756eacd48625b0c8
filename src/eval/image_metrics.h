#pragma once
// Full-reference image metrics on the RGB channels of two equally sized images with values in [0, 1].
#include "core/image.h"

namespace u3d {

// PSNR caps here: identical images would otherwise give +inf, which no mean or JSON file survives.
inline constexpr double kPsnrCapDb = 100.0;

// Mean squared error over all pixels and the R, G, B channels.
double mean_squared_error(const Image& a, const Image& b);

// 10 log10(1 / MSE) in dB (peak value 1), at most kPsnrCapDb.
double psnr(const Image& a, const Image& b);

// SSIM (Wang et al. 2004): 11x11 Gaussian window with sigma 1.5, K1 = 0.01, K2 = 0.03, dynamic range
// 1; the SSIM map is computed per RGB channel (borders reflected) and averaged over pixels and channels.
double ssim(const Image& a, const Image& b);

}  // namespace u3d
