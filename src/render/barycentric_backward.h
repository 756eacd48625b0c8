#pragma once
// Backward of the rasterizer's perspective-correct barycentrics: how (b1, b2) at a fixed pixel centre
// move when the triangle's projected vertices move (nvdiffrast's rasterize gradient). Coverage itself is
// not differentiable; silhouettes get their gradient from antialias instead.
#include <cstdint>
#include <span>
#include <vector>

#include "core/image.h"
#include "render/rasterizer.h"
#include "render/screen_projection.h"

namespace u3d {

// Adds dL/d(pixel xy, w) of each face vertex into `screen` from dL/d(b1, b2) at `pixels`.
void barycentric_backward(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                          const ScreenProjection& projection, const std::vector<Vec2f>& grad_bary,
                          ScreenGradient& screen);

// Orthographic cameras only (projection.orthographic): interpolate_backward followed by
// barycentric_backward in one pass over the pixels, for at most four channels. There the barycentrics
// are affine in the pixel centre q, so both results only need, per face and channel, the sums of the
// output gradient g and of g q: no per-pixel barycentric gradient is stored, and the vertices are
// visited once per face instead of once per pixel. The attribute gradient uses the barycentrics of the
// projected (unsnapped) vertices rather than the raster's stored ones; they differ by the raster's
// 1/256-pixel vertex snapping. Only the first `channels` channels are used; attributes and
// grad_attributes hold grad_out.channels values per vertex. Adds into grad_attributes and `screen`.
void interpolate_barycentric_backward_orthographic(const RasterBuffer& raster, std::span<const int32_t> pixels,
                                                   const std::vector<Vec3i>& faces, const float* attributes,
                                                   int channels, const ScreenProjection& projection,
                                                   const Image& grad_out, float* grad_attributes,
                                                   ScreenGradient& screen);

}  // namespace u3d
