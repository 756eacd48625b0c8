#pragma once
// Finite-difference checking of analytic gradients w.r.t. vertex positions.
#include <cmath>
#include <functional>
#include <vector>

#include "core/mesh.h"

namespace u3d::test {

// Loss of positions; when grad is non-null it must be filled (sized like positions) with dL/dp.
using LossFn = std::function<double(const std::vector<u3d::Vec3f>&, std::vector<u3d::Vec3f>*)>;

struct GradientComparison {
  std::vector<u3d::Vec3f> analytic;
  std::vector<u3d::Vec3f> numeric;
  double relative_error = 0.0;  // |a - n| / |n| over all coordinates
  double cosine = 0.0;
};

inline GradientComparison compare_gradients(const LossFn& loss, const std::vector<u3d::Vec3f>& positions,
                                            const std::vector<int>& vertices, float step) {
  GradientComparison c;
  std::vector<u3d::Vec3f> full(positions.size(), u3d::Vec3f::Zero());
  loss(positions, &full);
  double diff2 = 0, num2 = 0, dot = 0, ana2 = 0;
  for (int v : vertices) {
    u3d::Vec3f n;
    for (int k = 0; k < 3; ++k) {
      std::vector<u3d::Vec3f> p = positions;
      p[v][k] += step;
      const double up = loss(p, nullptr);
      p[v][k] -= 2 * step;
      const double down = loss(p, nullptr);
      n[k] = float((up - down) / (2 * step));
    }
    c.analytic.push_back(full[v]);
    c.numeric.push_back(n);
    diff2 += (full[v] - n).squaredNorm();
    num2 += n.squaredNorm();
    ana2 += full[v].squaredNorm();
    dot += full[v].dot(n);
  }
  c.relative_error = std::sqrt(diff2 / std::max(num2, 1e-30));
  c.cosine = dot / std::sqrt(std::max(num2 * ana2, 1e-30));
  return c;
}

}  // namespace u3d::test
