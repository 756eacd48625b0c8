#include "render/interpolate.h"

namespace u3d {

namespace {

// The loops are written once with the channel count as a template parameter: for the common counts
// (RGBA, RGB) the compiler unrolls and vectorizes the per-channel work, which a run-time count prevents.
template <int kFixed>
struct Channels {
  int count() const { return kFixed; }
};
template <>
struct Channels<0> {
  int n;
  int count() const { return n; }
};

template <int kFixed>
void interpolate_pixels(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                        const float* attributes, Channels<kFixed> ch, Image& out) {
  const int channels = ch.count();
  for (int32_t p : pixels) {
    const Vec3i& f = faces[raster.face_id[p]];
    const float b1 = raster.bary[p].x(), b2 = raster.bary[p].y(), b0 = 1.f - b1 - b2;
    const float* a0 = attributes + size_t(f[0]) * channels;
    const float* a1 = attributes + size_t(f[1]) * channels;
    const float* a2 = attributes + size_t(f[2]) * channels;
    float* o = out.data.data() + size_t(p) * channels;
    for (int c = 0; c < channels; ++c) o[c] = b0 * a0[c] + b1 * a1[c] + b2 * a2[c];
  }
}

template <int kFixed>
void interpolate_pixels_backward(const RasterBuffer& raster, std::span<const int32_t> pixels,
                                 const std::vector<Vec3i>& faces, const float* attributes, Channels<kFixed> ch,
                                 const Image& grad_out, float* grad_attributes, std::vector<Vec2f>* grad_bary) {
  const int channels = ch.count();
  for (int32_t p : pixels) {
    const Vec3i& f = faces[raster.face_id[p]];
    const float b1 = raster.bary[p].x(), b2 = raster.bary[p].y(), b0 = 1.f - b1 - b2;
    const float* g = grad_out.data.data() + size_t(p) * channels;
    const float* a0 = attributes + size_t(f[0]) * channels;
    const float* a1 = attributes + size_t(f[1]) * channels;
    const float* a2 = attributes + size_t(f[2]) * channels;
    float* g0 = grad_attributes + size_t(f[0]) * channels;
    float* g1 = grad_attributes + size_t(f[1]) * channels;
    float* g2 = grad_attributes + size_t(f[2]) * channels;
    float db1 = 0.f, db2 = 0.f;
    for (int c = 0; c < channels; ++c) {
      g0[c] += b0 * g[c];
      g1[c] += b1 * g[c];
      g2[c] += b2 * g[c];
      // b0 = 1 - b1 - b2, so each of b1, b2 also moves the weight of vertex 0.
      db1 += g[c] * (a1[c] - a0[c]);
      db2 += g[c] * (a2[c] - a0[c]);
    }
    if (grad_bary) (*grad_bary)[p] = {db1, db2};
  }
}

}  // namespace

std::vector<int32_t> covered_pixels(const RasterBuffer& raster) {
  std::vector<int32_t> pixels;
  covered_pixels(raster, pixels);
  return pixels;
}

void covered_pixels(const RasterBuffer& raster, std::vector<int32_t>& pixels) {
  pixels.clear();
  const PixelRect& r = raster.footprint;
  for (int y = r.y0; y <= r.y1; ++y)
    for (int x = r.x0, p = y * raster.width + r.x0; x <= r.x1; ++x, ++p)
      if (raster.face_id[p] >= 0) pixels.push_back(p);
}

void interpolate(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                 const float* attributes, int channels, Image& out) {
  switch (channels) {
    case 4: return interpolate_pixels(raster, pixels, faces, attributes, Channels<4>{}, out);
    case 3: return interpolate_pixels(raster, pixels, faces, attributes, Channels<3>{}, out);
    default: return interpolate_pixels(raster, pixels, faces, attributes, Channels<0>{channels}, out);
  }
}

void interpolate_backward(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                          const float* attributes, int channels, const Image& grad_out, float* grad_attributes,
                          std::vector<Vec2f>* grad_bary) {
  switch (channels) {
    case 4:
      return interpolate_pixels_backward(raster, pixels, faces, attributes, Channels<4>{}, grad_out, grad_attributes,
                                         grad_bary);
    case 3:
      return interpolate_pixels_backward(raster, pixels, faces, attributes, Channels<3>{}, grad_out, grad_attributes,
                                         grad_bary);
    default:
      return interpolate_pixels_backward(raster, pixels, faces, attributes, Channels<0>{channels}, grad_out,
                                         grad_attributes, grad_bary);
  }
}

}  // namespace u3d
