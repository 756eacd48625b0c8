#include "render/texture_sampler.h"

#include <algorithm>
#include <cmath>

namespace u3d {

namespace {

float wrap_unit(float t) { return (t >= 0.f && t <= 1.f) ? t : t - std::floor(t); }

Vec4f texel(const Image& tex, int x, int y) {
  const float* p = tex.pixel(x, y);
  switch (tex.channels) {
    case 1: return {p[0], p[0], p[0], 1.f};
    case 2: return {p[0], p[0], p[0], p[1]};
    case 3: return {p[0], p[1], p[2], 1.f};
    default: return {p[0], p[1], p[2], p[3]};
  }
}

}  // namespace

Vec4f sample_texture(const Image& tex, const Vec2f& uv) {
  if (tex.empty()) return Vec4f::Ones();
  // Continuous texel coordinates with texel centres at integers.
  float x = wrap_unit(uv.x()) * float(tex.width) - 0.5f;
  float y = (1.f - wrap_unit(uv.y())) * float(tex.height) - 0.5f;
  float fx = std::floor(x), fy = std::floor(y);
  float tx = x - fx, ty = y - fy;
  int x0 = std::clamp(int(fx), 0, tex.width - 1), x1 = std::clamp(int(fx) + 1, 0, tex.width - 1);
  int y0 = std::clamp(int(fy), 0, tex.height - 1), y1 = std::clamp(int(fy) + 1, 0, tex.height - 1);
  return (1.f - ty) * ((1.f - tx) * texel(tex, x0, y0) + tx * texel(tex, x1, y0)) +
         ty * ((1.f - tx) * texel(tex, x0, y1) + tx * texel(tex, x1, y1));
}

}  // namespace u3d
