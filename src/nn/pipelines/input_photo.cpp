#include "nn/pipelines/input_photo.h"

#include <cmath>

#include "core/error.h"
#include "core/progress.h"
#include "core/solid_matte.h"
#include "nn/preprocess/pil_resize.h"

namespace u3d::nn {
namespace {

// PIL's rounded division by 255 (its BLEND/PREBLEND macros).
inline uint8_t div255(int value) {
  const int t = value + 128;
  return static_cast<uint8_t>((t + (t >> 8)) >> 8);
}

}  // namespace

std::pair<int64_t, int64_t> thumbnail_size(int64_t width, int64_t height, int64_t max_side) {
  if (width <= max_side && height <= max_side) return {width, height};
  const double aspect = double(width) / double(height);
  // Of floor and ceil, the one whose aspect error is smaller (floor on ties), at least 1.
  auto pick = [](double value, auto error) {
    const double lo = std::floor(value), hi = std::ceil(value);
    return static_cast<int64_t>(std::max(error(hi) < error(lo) ? hi : lo, 1.0));
  };
  if (1.0 >= aspect)  // max_side / max_side >= aspect: the height is the limit
    return {pick(max_side * aspect, [&](double n) { return std::abs(aspect - n / max_side); }), max_side};
  return {max_side, pick(max_side / aspect, [&](double n) { return n == 0 ? 0.0 : std::abs(aspect - max_side / n); })};
}

torch::Tensor colours_on_white(const torch::Tensor& rgba) {
  require(rgba.dim() == 3 && rgba.size(2) == 4 && rgba.scalar_type() == torch::kUInt8,
          "colours_on_white: expected a uint8 RGBA image [H, W, 4]");
  torch::Tensor out = rgba.contiguous().clone();
  uint8_t* p = out.data_ptr<uint8_t>();
  const int64_t pixels = rgba.size(0) * rgba.size(1);
  for (int64_t i = 0; i < pixels; ++i) {
    const int a = p[i * 4 + 3];
    for (int k = 0; k < 3; ++k) p[i * 4 + k] = div255(p[i * 4 + k] * a + 255 * (255 - a));
  }
  return out;
}

torch::Tensor simple_preprocess(const torch::Tensor& rgba) {
  require(rgba.dim() == 3 && rgba.size(2) == 4 && rgba.scalar_type() == torch::kUInt8,
          "simple_preprocess: expected a uint8 RGBA image [H, W, 4]");
  torch::Tensor image = rgba;
  const auto [w, h] = thumbnail_size(rgba.size(1), rgba.size(0), kInputPhotoMaxSide);
  if (w != rgba.size(1) || h != rgba.size(0)) image = pil_resize(rgba, w, h, PilFilter::Lanczos);

  const torch::Tensor fg = image.select(2, 3) > kForegroundAlpha;
  const torch::Tensor rows = fg.any(1).nonzero(), cols = fg.any(0).nonzero();
  require(rows.numel() > 0, "simple_preprocess: no pixel of the photo has an alpha above 60 (nothing to crop to)");
  const int64_t y0 = rows.min().item<int64_t>(), y1 = rows.max().item<int64_t>();
  const int64_t x0 = cols.min().item<int64_t>(), x1 = cols.max().item<int64_t>();
  const torch::Tensor crop = image.slice(0, y0, y1).slice(1, x0, x1);  // end exclusive, as the official slice
  const int64_t ch = crop.size(0), cw = crop.size(1), side = std::max(ch, cw);
  if (ch == cw) return crop.contiguous();
  torch::Tensor square = torch::empty({side, side, 4}, torch::kUInt8);
  square.slice(2, 0, 3).fill_(255);
  square.select(2, 3).fill_(0);
  const int64_t top = cw > ch ? (cw - ch) / 2 : 0, left = ch > cw ? (ch - cw) / 2 : 0;
  square.slice(0, top, top + ch).slice(1, left, left + cw).copy_(crop);
  return square;
}

torch::Tensor matte_photo(const torch::Tensor& image, MattingModel& model, bool raw_matte) {
  require(image.dim() == 3 && (image.size(2) == 3 || image.size(2) == 4) && image.scalar_type() == torch::kUInt8,
          "matte_photo: expected a uint8 RGB or RGBA image [H, W, 3|4]");
  torch::Tensor mask = model.matte(image.slice(2, 0, 3).contiguous()).contiguous();
  if (!raw_matte) {
    Image alpha(int(mask.size(1)), int(mask.size(0)), 1);
    const uint8_t* m = mask.data_ptr<uint8_t>();
    for (size_t i = 0; i < alpha.data.size(); ++i) alpha.data[i] = float(m[i]) / 255.f;
    const Image solid = solid_matte(alpha);
    uint8_t* out = mask.data_ptr<uint8_t>();
    for (size_t i = 0; i < solid.data.size(); ++i) out[i] = static_cast<uint8_t>(std::lround(solid.data[i] * 255.f));
  }
  return cutout(image, mask, MattingStyle::kRembg);
}

torch::Tensor prepare_input_photo(const torch::Tensor& image, const InputPhotoModels& models, bool remove_background,
                                  bool raw_matte) {
  require(image.dim() == 3 && (image.size(2) == 3 || image.size(2) == 4) && image.scalar_type() == torch::kUInt8,
          "prepare_input_photo: expected a uint8 RGB or RGBA image [H, W, 3|4]");
  // Opaque is a property of the photo, decided before the upscaler, whose alpha of an opaque photo need
  // not stay 255 everywhere: an opaque photo is upscaled as RGB, as one without alpha is.
  const bool opaque = image.size(2) == 3 || (image.select(2, 3) == 255).all().item<bool>();
  torch::Tensor photo = opaque ? image.slice(2, 0, 3).contiguous() : image;
  if (photo.size(1) <= kSuperResolveMaxWidth) {
    const auto upscaler = models.upscaler();
    StageTimer stage("upscale input photo");
    photo = upscaler->upscale(photo);
  }
  if (remove_background || opaque) {
    const auto matting = models.matting();
    StageTimer stage("remove background");
    photo = matte_photo(photo, *matting, raw_matte);
  }
  return simple_preprocess(colours_on_white(photo));
}

}  // namespace u3d::nn
