#pragma once
// sRGB transfer functions (IEC 61966-2-1, the exact piecewise curve). Colours are sRGB-encoded in
// memory; formats that store linear values (glTF COLOR_0 and baseColorFactor) convert at the boundary.
// Computed in double so that 0 and 1 map exactly onto 0 and 1 and round trips lose nothing visible.
#include <cmath>

namespace u3d {

inline float srgb_to_linear(float c) {
  double v = c;
  return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

inline float linear_to_srgb(float c) {
  double v = c;
  return float(v <= 0.0031308 ? v * 12.92 : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055);
}

}  // namespace u3d
