#include "pipeline/tensor_image.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace u3d {

torch::Tensor image_to_uint8(const Image& image) {
  const bool gray = image.channels < 3;
  const bool alpha = image.channels == 2 || image.channels == 4;
  const int out_channels = alpha ? 4 : 3;
  torch::Tensor out = torch::empty({image.height, image.width, out_channels}, torch::kUInt8);
  uint8_t* o = out.data_ptr<uint8_t>();
  const auto u8 = [](float v) { return uint8_t(std::lround(std::clamp(v, 0.f, 1.f) * 255.f)); };
  for (size_t i = 0; i < image.pixel_count(); ++i) {
    const float* p = image.data.data() + i * image.channels;
    for (int c = 0; c < 3; ++c) o[i * out_channels + c] = u8(p[gray ? 0 : c]);
    if (alpha) o[i * out_channels + 3] = u8(p[image.channels - 1]);
  }
  return out;
}

Image tensor_to_image(const torch::Tensor& hwc) {
  // 8-bit values times float(1 / 255), as the PNG and JPEG decoders scale them (core/image_decode.cpp): an
  // image read back from a file it was saved to is then the same to the bit, so a run resumed from kept
  // intermediates gives the same output as one that never stopped (dividing by 255 differs in the last
  // bit for about one value in five).
  torch::Tensor t = hwc.scalar_type() == torch::kUInt8 ? hwc.to(torch::kFloat).mul(float(1.0 / 255.0))
                                                       : hwc.to(torch::kFloat).clamp(0, 1);
  t = t.contiguous();
  Image image(int(t.size(1)), int(t.size(0)), int(t.size(2)));
  std::memcpy(image.data.data(), t.data_ptr<float>(), image.data.size() * sizeof(float));
  return image;
}

}  // namespace u3d
