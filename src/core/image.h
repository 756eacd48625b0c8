#pragma once
// Image: interleaved float channels, row-major, row 0 at the top of the picture (see docs/conventions.md).
// Colour values are kept as stored in the file (sRGB-encoded for ordinary photos), scaled to [0, 1];
// channel order is R, G, B, A. Gray images have 1 channel.
#include <cstddef>
#include <filesystem>
#include <vector>

namespace u3d {

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> data;  // width * height * channels

  Image() = default;
  Image(int w, int h, int c, float fill = 0.f);

  bool empty() const { return data.empty(); }
  size_t pixel_count() const { return size_t(width) * size_t(height); }
  float& at(int x, int y, int c) { return data[(size_t(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const { return data[(size_t(y) * width + x) * channels + c]; }
  float* pixel(int x, int y) { return data.data() + (size_t(y) * width + x) * channels; }
  const float* pixel(int x, int y) const { return data.data() + (size_t(y) * width + x) * channels; }
};

// Loads a PNG or JPEG file (8 or 16 bit, gray/RGB/RGBA; core/image_decode.h) to floats in [0, 1],
// RGB(A) order, alpha kept. Throws Error naming the file if it is missing, unreadable or not a PNG or
// JPEG image (other formats are refused by their content, whatever the file is called).
Image load_image(const std::filesystem::path& path);

// Same, always 4 channels: gray is replicated, missing alpha becomes 1.
Image load_image_rgba(const std::filesystem::path& path);

// Writes by extension (.png: 8 or 16 bit, alpha kept; .jpg: 8 bit, alpha dropped), atomically.
// Values are clamped to [0, 1]; NaN is rejected with an Error.
void save_image(const Image& image, const std::filesystem::path& path, int bit_depth = 8);

// The image as save_image writes it at 8 bits and load_image reads it back: each value clamped to [0, 1]
// and rounded to the nearest of 256 levels, bit for bit what the file gives.
Image quantized_8bit(const Image& image);

// Bilinear/area resize (OpenCV INTER_AREA when shrinking, INTER_LINEAR when enlarging).
Image resize_image(const Image& image, int width, int height);

// resize_image of an RGBA image with its colour weighted by alpha (premultiplied, resized, divided by the
// resized alpha again; 0 where that is 0 or below 1e-6), so the colour of transparent pixels does not
// bleed into the object's edges. Throws Error unless the image has 4 channels.
Image resize_premultiplied(const Image& rgba, int width, int height);

}  // namespace u3d
