// Integrating analytic normal fields must recover their height fields (pixel units).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "isomer/normal_integration.h"

namespace u3d {
namespace {

struct Field {
  int size = 0;
  std::vector<Vec3f> normals;
  std::vector<uint8_t> mask;
  std::vector<float> truth;
};

// Disk of radius `radius` pixels centred in a size x size map; z(u, v) in pixel units, with u right
// and v down from the map centre. Normals are computed from the analytic gradient.
Field make_field(int size, float radius, const std::function<float(float, float)>& z,
                 const std::function<Eigen::Vector2f(float, float)>& grad_uv) {
  Field f;
  f.size = size;
  f.normals.assign(size_t(size) * size, Vec3f(0, 0, 1));
  f.mask.assign(f.normals.size(), 0);
  f.truth.assign(f.normals.size(), 0.f);
  const float c = 0.5f * (size - 1);
  for (int v = 0; v < size; ++v)
    for (int u = 0; u < size; ++u) {
      const float x = u - c, y = v - c;
      if (x * x + y * y > radius * radius) continue;
      const size_t i = size_t(v) * size + u;
      const Eigen::Vector2f g = grad_uv(x, y);
      // dz/du = -n_x/n_z, dz/dv = +n_y/n_z  ->  n ~ (-dz/du, dz/dv, 1)
      f.normals[i] = Vec3f(-g.x(), g.y(), 1.f).normalized();
      f.mask[i] = 1;
      f.truth[i] = z(x, y);
    }
  return f;
}

// Max |estimate - truth| over the mask after removing the mean difference (the height reference),
// optionally ignoring pixels within `rim` pixels of the mask border.
float max_error(const Field& f, const std::vector<float>& est, float radius, float rim, bool remove_offset) {
  const float c = 0.5f * (f.size - 1);
  double offset = 0;
  size_t count = 0;
  for (size_t i = 0; i < est.size(); ++i)
    if (f.mask[i]) offset += est[i] - f.truth[i], ++count;
  offset = remove_offset ? offset / double(count) : 0.0;
  float worst = 0.f;
  for (int v = 0; v < f.size; ++v)
    for (int u = 0; u < f.size; ++u) {
      const size_t i = size_t(v) * f.size + u;
      const float x = u - c, y = v - c;
      if (!f.mask[i] || std::sqrt(x * x + y * y) > radius - rim) continue;
      worst = std::max(worst, float(std::abs(est[i] - f.truth[i] - offset)));
    }
  return worst;
}

TEST(NormalIntegration, FlatPlaneGivesZeroHeight) {
  Field f = make_field(128, 50, [](float, float) { return 0.f; }, [](float, float) { return Eigen::Vector2f(0, 0); });
  std::vector<float> h = integrate_normal_map(f.normals, f.mask, f.size, f.size);
  EXPECT_LT(max_error(f, h, 50, 0, false), 1e-3f);
}

TEST(NormalIntegration, TiltedPlaneIsRecoveredUpToAConstant) {
  const float a = 0.4f, b = -0.25f;  // slopes per pixel along u and v
  Field f = make_field(128, 50, [&](float x, float y) { return a * x + b * y; },
                       [&](float, float) { return Eigen::Vector2f(a, b); });
  std::vector<float> h = integrate_normal_map(f.normals, f.mask, f.size, f.size);
  // Heights span 2 * 50 * |(a, b)| ~ 47 px; tolerance: 0.5 px.
  EXPECT_LT(max_error(f, h, 50, 0, true), 0.5f);
}

TEST(NormalIntegration, TiltedPlaneWithoutMeanSlopeRemovalIsFlattened) {
  // Documents why remove_mean_slope exists: the rim-anchored average halves a plane's slope.
  const float a = 0.4f;
  Field f = make_field(128, 50, [&](float x, float) { return a * x; }, [&](float, float) { return Eigen::Vector2f(a, 0); });
  NormalIntegrationOptions options;
  options.remove_mean_slope = false;
  std::vector<float> h = integrate_normal_map(f.normals, f.mask, f.size, f.size, options);
  const int c = 64;
  const float right = h[size_t(c) * f.size + c + 40], left = h[size_t(c) * f.size + c - 40];
  EXPECT_NEAR((right - left) / 80.f, 0.5f * a, 0.05f);
}

TEST(NormalIntegration, SphereCapIsRecoveredWithZeroRim) {
  // Cap of a sphere of radius 80 px cut where the rim radius is 60 px: rim slope is finite.
  const float R = 80.f, rim = 60.f, cut = std::sqrt(R * R - rim * rim);
  Field f = make_field(160, rim, [&](float x, float y) { return std::sqrt(R * R - x * x - y * y) - cut; },
                       [&](float x, float y) {
                         const float zz = std::sqrt(R * R - x * x - y * y);
                         return Eigen::Vector2f(-x / zz, -y / zz);
                       });
  std::vector<float> h = integrate_normal_map(f.normals, f.mask, f.size, f.size);
  // Cap height is R - cut = 27 px. Absolute error (no offset removed): within 1 px everywhere.
  EXPECT_LT(max_error(f, h, rim, 0, false), 1.0f);
  // Interior (away from the rim) within 0.6 px.
  EXPECT_LT(max_error(f, h, rim, 5, false), 0.6f);
}

TEST(NormalIntegration, MaskIsRespected) {
  // Two disks of different heights side by side: integration must not leak across the background.
  const int size = 128;
  std::vector<Vec3f> normals(size_t(size) * size, Vec3f(0, 0, 1));
  std::vector<uint8_t> mask(normals.size(), 0);
  for (int v = 0; v < size; ++v)
    for (int u = 0; u < size; ++u) {
      const float x1 = u - 32.f, x2 = u - 96.f, y = v - 64.f;
      if (x1 * x1 + y * y < 25 * 25 || x2 * x2 + y * y < 25 * 25) mask[size_t(v) * size + u] = 1;
    }
  std::vector<float> h = integrate_normal_map(normals, mask, size, size);
  for (size_t i = 0; i < h.size(); ++i) {
    if (!mask[i]) EXPECT_EQ(h[i], 0.f);
    else EXPECT_NEAR(h[i], 0.f, 1e-3f);
  }
}

}  // namespace
}  // namespace u3d
