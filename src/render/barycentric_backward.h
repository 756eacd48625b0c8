#pragma once
// Backward of the rasterizer's perspective-correct barycentrics: how (b1, b2) at a fixed pixel centre
// move when the triangle's projected vertices move (nvdiffrast's rasterize gradient). Coverage itself is
// not differentiable; silhouettes get their gradient from antialias instead.
#include <cstdint>
#include <span>
#include <vector>

#include "render/rasterizer.h"
#include "render/screen_projection.h"

namespace u3d {

// Adds dL/d(pixel xy, w) of each face vertex into `screen` from dL/d(b1, b2) at `pixels`.
void barycentric_backward(const RasterBuffer& raster, std::span<const int32_t> pixels, const std::vector<Vec3i>& faces,
                          const ScreenProjection& projection, const std::vector<Vec2f>& grad_bary,
                          ScreenGradient& screen);

}  // namespace u3d
