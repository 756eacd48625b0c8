#pragma once
// The interpolate primitive (as nvdiffrast's `interpolate`): per-vertex attributes -> per-pixel values
// with the rasterizer's barycentrics, and its backward pass to the attributes and to the barycentrics.
// Both work on an explicit list of covered pixels so callers pay only for the object's footprint.
#include <cstdint>
#include <span>
#include <vector>

#include "core/image.h"
#include "render/rasterizer.h"

namespace u3d {

// Indices of the pixels a triangle covers, in scanline order.
std::vector<int32_t> covered_pixels(const RasterBuffer& raster);
// The same into `pixels`, reusing its storage (for frame-by-frame rendering).
void covered_pixels(const RasterBuffer& raster, std::vector<int32_t>& pixels);

// out(pixel, c) = sum_i b_i * attributes[v_i * channels + c] for every pixel in `pixels` (all covered).
// `out` must be raster-sized with `channels` channels; other pixels are left untouched.
void interpolate(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                 const float* attributes, int channels, Image& out);

// Backward of interpolate for the same pixels: adds dL/d(attributes) into grad_attributes
// (vertex_count * channels) and, if grad_bary is non-null, writes dL/d(b1, b2) per pixel
// (grad_bary must be raster-sized; only `pixels` are written).
void interpolate_backward(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                          const float* attributes, int channels, const Image& grad_out, float* grad_attributes,
                          std::vector<Vec2f>* grad_bary);

}  // namespace u3d
