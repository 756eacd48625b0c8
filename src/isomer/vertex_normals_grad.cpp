#include "isomer/vertex_normals_grad.h"

#include <Eigen/Geometry>
#include <algorithm>

namespace u3d {

namespace {
constexpr float kMinNorm = 1e-6f;  // as torch's normalize(eps=1e-6)
}

VertexNormals compute_vertex_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces) {
  std::vector<Vec3f> sum(positions.size(), Vec3f::Zero());
  for (const Vec3i& f : faces) {
    const Vec3f n = (positions[f[1]] - positions[f[0]]).cross(positions[f[2]] - positions[f[0]]);
    sum[f[0]] += n;
    sum[f[1]] += n;
    sum[f[2]] += n;
  }
  VertexNormals out;
  out.unit.resize(positions.size());
  out.norm.resize(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    const float len = sum[v].norm();
    out.norm[v] = len;
    out.unit[v] = sum[v] / std::max(len, kMinNorm);
  }
  return out;
}

void vertex_normals_backward(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                             const VertexNormals& normals, const std::vector<Vec3f>& grad_unit,
                             std::vector<Vec3f>& grad_positions) {
  // d(s/|s|)/ds = (I - n n^T) / |s|.
  std::vector<Vec3f> grad_sum(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    const Vec3f& g = grad_unit[v];
    const float len = normals.norm[v];
    if (len < kMinNorm) {
      grad_sum[v] = g / kMinNorm;
      continue;
    }
    const Vec3f& n = normals.unit[v];
    grad_sum[v] = (g - n * n.dot(g)) / len;
  }
  // Face normal n = (p1 - p0) x (p2 - p0) feeds all three corners' sums.
  for (const Vec3i& f : faces) {
    const Vec3f gn = grad_sum[f[0]] + grad_sum[f[1]] + grad_sum[f[2]];
    if (gn.isZero(0.f)) continue;
    const Vec3f e1 = positions[f[1]] - positions[f[0]], e2 = positions[f[2]] - positions[f[0]];
    // d/de1 <gn, e1 x e2> = e2 x gn ; d/de2 = gn x e1.
    const Vec3f g1 = e2.cross(gn), g2 = gn.cross(e1);
    grad_positions[f[1]] += g1;
    grad_positions[f[2]] += g2;
    grad_positions[f[0]] -= g1 + g2;
  }
}

}  // namespace u3d
