#include "geometry/surface_sampling.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace u3d {

namespace {

double triangle_area(const std::vector<Vec3f>& p, const Vec3i& f) {
  Eigen::Vector3d a = p[f[0]].cast<double>(), b = p[f[1]].cast<double>(), c = p[f[2]].cast<double>();
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace

double surface_area(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces) {
  double total = 0;
  for (const auto& f : faces) total += triangle_area(positions, f);
  return total;
}

SurfaceSamples sample_surface(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, size_t count,
                              uint64_t seed) {
  // Cumulative areas in double: with a million faces float sums lose the small triangles.
  std::vector<double> cumulative(faces.size());
  double total = 0;
  for (size_t f = 0; f < faces.size(); ++f) cumulative[f] = total += triangle_area(positions, faces[f]);
  require(total > 0 && std::isfinite(total), "cannot sample the surface of a mesh with zero area");

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  SurfaceSamples out;
  out.points.reserve(count);
  out.faces.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    double target = uniform(rng) * total;
    size_t f = std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin();
    f = std::min(f, faces.size() - 1);
    // Square-root warp: (u, v) uniform in the unit square -> uniform barycentrics on the triangle.
    double su = std::sqrt(uniform(rng)), v = uniform(rng);
    float b0 = float(1 - su), b1 = float(su * (1 - v)), b2 = float(su * v);
    const Vec3i& t = faces[f];
    out.points.push_back(b0 * positions[t[0]] + b1 * positions[t[1]] + b2 * positions[t[2]]);
    out.faces.push_back(int(f));
  }
  return out;
}

}  // namespace u3d
