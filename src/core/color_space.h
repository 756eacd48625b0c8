#pragma once
// sRGB transfer functions (IEC 61966-2-1, the exact piecewise curve). Colours are sRGB-encoded in
// memory; formats that store linear values (glTF COLOR_0 and baseColorFactor) convert at the boundary.
#include <cmath>

namespace u3d {

inline float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

inline float linear_to_srgb(float c) {
  return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.f / 2.4f) - 0.055f;
}

}  // namespace u3d
