// PSNR and SSIM against values computable by hand, and the 24-view appearance comparison.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "eval/appearance.h"
#include "eval/image_metrics.h"
#include "geometry/test_shapes.h"

using namespace u3d;

namespace {

Image constant_image(int w, int h, float value) { return Image(w, h, 3, value); }

Mesh colored_sphere(const Vec3f& color) {
  Mesh m = test::sphere_mesh(0.5f, 2);
  m.colors.assign(m.positions.size(), color);
  return m;
}

}  // namespace

TEST(ImageMetrics, IdenticalImagesArePerfect) {
  Image a(32, 24, 3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (auto& v : a.data) v = u(rng);
  EXPECT_EQ(mean_squared_error(a, a), 0.0);
  EXPECT_EQ(psnr(a, a), kPsnrCapDb);
  EXPECT_NEAR(ssim(a, a), 1.0, 1e-12);
}

TEST(ImageMetrics, ConstantOffsetGivesKnownPsnrAndSsim) {
  Image a = constant_image(20, 20, 0.5f), b = constant_image(20, 20, 0.6f);
  EXPECT_NEAR(mean_squared_error(a, b), 0.01, 1e-7);
  EXPECT_NEAR(psnr(a, b), 20.0, 1e-5);
  // No variance anywhere: SSIM reduces to the luminance term (2 mu_x mu_y + C1) / (mu_x^2 + mu_y^2 + C1).
  const double c1 = 1e-4, expected = (2 * 0.5 * 0.6 + c1) / (0.25 + 0.36 + c1);
  EXPECT_NEAR(ssim(a, b), expected, 1e-6);
}

TEST(ImageMetrics, NoiseLowersSsimSymmetrically) {
  Image a(40, 40, 3, 0.5f), b = a;
  std::mt19937 rng(4);
  std::normal_distribution<float> n(0, 0.1f);
  for (auto& v : b.data) v += n(rng);
  double s = ssim(a, b);
  EXPECT_LT(s, 0.9);
  EXPECT_GT(s, 0.0);
  EXPECT_NEAR(ssim(b, a), s, 1e-12);
  EXPECT_NEAR(psnr(a, b), 20.0, 0.5);  // sigma 0.1 -> MSE ~ 0.01
}

TEST(ImageMetrics, MismatchedImagesAreAnError) {
  EXPECT_THROW(psnr(Image(4, 4, 3), Image(4, 5, 3)), Error);
  EXPECT_THROW(ssim(Image(4, 4, 3), Image(4, 4, 1)), Error);
}

TEST(Appearance, ProtocolHas24ViewsAtThreeElevations) {
  auto views = evaluation_views();
  ASSERT_EQ(views.size(), 24u);
  EXPECT_EQ(views[0].elevation_deg, 0.f);
  EXPECT_EQ(views[8].elevation_deg, 15.f);
  EXPECT_EQ(views[23].elevation_deg, 30.f);
  EXPECT_EQ(views[7].azimuth_deg, 315.f);
}

TEST(Appearance, IdenticalMeshesScorePerfectly) {
  Mesh m = colored_sphere({0.8f, 0.3f, 0.1f});
  AppearanceMetrics a = appearance_metrics(m, m, {64, 1});
  ASSERT_EQ(a.views.size(), 24u);
  EXPECT_NEAR(a.psnr, kPsnrCapDb, 1e-9);
  EXPECT_NEAR(a.ssim, 1.0, 1e-9);
}

TEST(Appearance, DifferentColorIsPenalised) {
  Mesh red = colored_sphere({1, 0, 0}), white = colored_sphere({1, 1, 1});
  AppearanceMetrics a = appearance_metrics(red, white, {64, 1});
  // Sphere of radius 0.5 in a view of half width 0.51 covers pi/4 * (0.5/0.51)^2 of the image, where
  // G and B differ by 1: MSE = coverage * 2/3.
  double coverage = 3.14159265 / 4 * (0.5 / 0.51) * (0.5 / 0.51);
  EXPECT_NEAR(a.psnr, -10 * std::log10(coverage * 2.0 / 3.0), 0.2);
  EXPECT_LT(a.ssim, 0.9);
}
