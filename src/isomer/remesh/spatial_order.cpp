#include "isomer/remesh/spatial_order.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>

namespace u3d {

namespace {

// The 10 low bits of v spread to every third bit.
uint32_t spread_bits(uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// A coordinate scaled to [0, 1023] as an integer; NaN (a diverged vertex) and anything below 0 give 0.
uint32_t quantize(float x) { return x >= 0.f ? uint32_t(std::min(x, 1023.f)) : 0u; }

}  // namespace

void reorder_spatially(VertexRows& rows, std::vector<Vec3i>& faces) {
  const size_t n = rows.count();
  if (n == 0) return;
  Eigen::AlignedBox3f box;
  for (size_t v = 0; v < n; ++v) box.extend(rows.position(v));
  const Vec3f lo = box.min();
  const Vec3f scale = (1023.f / box.sizes().cwiseMax(1e-12f).array()).matrix();
  // Sorting (key << 32 | index) keys orders by key and breaks ties by index: a stable order, without
  // the indirect comparisons of sorting indices by a looked-up key.
  std::vector<uint64_t> keys(n);
  for (size_t v = 0; v < n; ++v) {
    const Vec3f q = (rows.position(v) - lo).cwiseProduct(scale);
    const uint32_t code =
        spread_bits(quantize(q.x())) | (spread_bits(quantize(q.y())) << 1) | (spread_bits(quantize(q.z())) << 2);
    keys[v] = (uint64_t(code) << 32) | v;
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int> new_of(n);
  std::vector<float> values(rows.values.size());
  for (size_t k = 0; k < n; ++k) {
    const size_t old = size_t(keys[k] & 0xffffffffu);
    new_of[old] = int(k);
    std::copy_n(rows.row(old), rows.stride, values.data() + k * size_t(rows.stride));
  }
  rows.values = std::move(values);
  keys.resize(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    Vec3i& face = faces[f];
    for (int i = 0; i < 3; ++i) face[i] = new_of[size_t(face[i])];
    keys[f] = (uint64_t(uint32_t(face.minCoeff())) << 32) | f;
  }
  std::sort(keys.begin(), keys.end());
  std::vector<Vec3i> sorted(faces.size());
  for (size_t k = 0; k < faces.size(); ++k) sorted[k] = faces[size_t(keys[k] & 0xffffffffu)];
  faces = std::move(sorted);
}

}  // namespace u3d
