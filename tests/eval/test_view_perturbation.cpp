// Perturbation of view sets: warps move pixels where geometry says, normals turn with the picture,
// noise is deterministic, and the folder-level command handles partial and bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/temp_dir.h"
#include "eval/view_perturbation.h"

using namespace u3d;
namespace fs = std::filesystem;

namespace {

Image single_dot(int size, int x, int y) {
  Image img(size, size, 4, 0.f);
  float* p = img.pixel(x, y);
  p[0] = 1, p[1] = 0.5f, p[2] = 0.25f, p[3] = 1;
  return img;
}

Vec3f normal_at(const Image& img, int x, int y) {
  const float* p = img.pixel(x, y);
  return Vec3f(2 * p[0] - 1, 2 * p[1] - 1, 2 * p[2] - 1);
}

Image flat_normal_map(int size, const Vec3f& n) {
  Image img(size, size, 4, 0.f);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      float* p = img.pixel(x, y);
      for (int c = 0; c < 3; ++c) p[c] = 0.5f * (n[c] + 1);
      p[3] = 1;
    }
  return img;
}

fs::path fresh_dir(const std::string& name) {
  return u3d::testing::fresh_temp_dir("perturb_" + name);
}

}  // namespace

TEST(WarpImage, IdentityKeepsPixels) {
  Image img = single_dot(16, 11, 5);
  Image out = warp_image(img, {0, 1}, false);
  EXPECT_EQ(out.data, img.data);
}

TEST(WarpImage, RotationIsCounterClockwiseAndScaleEnlarges) {
  Image img = single_dot(17, 12, 8);  // centre pixel is (8, 8): dot 4 px to the right
  Image rotated = warp_image(img, {90, 1}, false);
  EXPECT_NEAR(rotated.pixel(8, 4)[3], 1.f, 1e-4f);  // now 4 px above the centre
  EXPECT_NEAR(rotated.pixel(8, 4)[0], 1.f, 1e-4f);
  EXPECT_NEAR(rotated.pixel(12, 8)[3], 0.f, 1e-4f);
  Image zoomed = warp_image(img, {0, 2}, false);
  EXPECT_GT(zoomed.pixel(16, 8)[3], 0.2f);  // 8 px to the right now
  EXPECT_NEAR(zoomed.pixel(12, 8)[3], 0.f, 1e-4f);
  // Colour is not darkened at the blurred edge: alpha-premultiplied interpolation.
  EXPECT_NEAR(zoomed.pixel(16, 8)[1], 0.5f, 1e-4f);
}

TEST(RotateNormals, TurnsAboutTheAxisByTheRightHandRule) {
  Image n = flat_normal_map(4, {1, 0, 0});
  rotate_normals(n, {0, 0, 1}, 90);
  EXPECT_TRUE(normal_at(n, 2, 2).isApprox(Vec3f(0, 1, 0), 1e-5f));
}

TEST(NormalNoise, DeterministicUnitLengthAndScaledBySigma) {
  Image a = flat_normal_map(32, {0, 0, 1}), b = a, c = a;
  a.pixel(0, 0)[3] = 0;  // background stays untouched
  b.pixel(0, 0)[3] = 0;
  add_normal_noise(a, 0.05f, 1);
  add_normal_noise(b, 0.05f, 1);
  add_normal_noise(c, 0.05f, 2);
  EXPECT_EQ(a.data, b.data);
  EXPECT_NE(a.data, c.data);
  EXPECT_TRUE(normal_at(a, 0, 0).isApprox(Vec3f(0, 0, 1)));
  double mean_tilt = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      Vec3f n = normal_at(a, x, y);
      EXPECT_NEAR(n.norm(), 1.f, 0.01f);
      mean_tilt += std::sqrt(n.x() * n.x() + n.y() * n.y()) / 1024.0;
    }
  // |(x, y)| of two N(0, s^2) components has mean s * sqrt(pi / 2).
  EXPECT_NEAR(mean_tilt, 0.05 * std::sqrt(3.14159265 / 2), 0.01);
}

TEST(PerturbViewSet, RollsOneViewWithItsNormalsAndCopiesTheRest) {
  fs::path in = fresh_dir("in"), out = fresh_dir("out");
  // Right view (camera on +X): a normal facing the camera stays, an upward normal turns toward +Z
  // (image left of the right view) under a 90-degree counter-clockwise roll.
  Image up = flat_normal_map(9, {0, 1, 0});
  save_image(up, in / "right_normal.png", 16);
  save_image(flat_normal_map(9, {1, 0, 0}), in / "front_normal.png", 16);
  save_image(single_dot(9, 4, 4), in / "front_rgb.png");
  std::ofstream(in / "notes.txt") << "kept";
  PerturbOptions o;
  o.warps[int(View::Right)] = {90, 1};
  o.seed = 1;
  perturb_view_set(in, out, o);
  Image right = load_image_rgba(out / "right_normal.png");
  EXPECT_TRUE(normal_at(right, 4, 4).isApprox(Vec3f(0, 0, 1), 1e-3f)) << normal_at(right, 4, 4).transpose();
  Image front = load_image_rgba(out / "front_normal.png");
  EXPECT_TRUE(normal_at(front, 4, 4).isApprox(Vec3f(1, 0, 0), 1e-3f));
  EXPECT_TRUE(fs::exists(out / "front_rgb.png"));
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  std::ifstream record(out / "perturbation.json");
  nlohmann::json j = nlohmann::json::parse(record);
  EXPECT_EQ(j["views"]["right"]["rotate_deg"].get<float>(), 90.f);
  fs::remove_all(in);
  fs::remove_all(out);
}

TEST(SmoothField, HasTheRequestedRmsAndIsSmoothAndSeeded) {
  const SmoothField field({2.f, 64.f}, 7), same({2.f, 64.f}, 7), other({2.f, 64.f}, 8);
  double sum_sq = 0, step_sq = 0;
  int n = 0;
  for (int y = 0; y < 512; y += 4)
    for (int x = 0; x < 512; x += 4, ++n) {
      const Eigen::Vector2f d = field.at(x, y);
      sum_sq += d.squaredNorm() / 2;
      step_sq += (field.at(x + 1, y) - d).squaredNorm() / 2;
    }
  EXPECT_NEAR(std::sqrt(sum_sq / n), 2.0, 0.4);
  // A sinusoid of wavelength 64 changes by at most 2 pi / 64 of its amplitude per pixel.
  EXPECT_LT(std::sqrt(step_sq / n), 2.0 * 2 * 3.1416 / 64);
  EXPECT_EQ(field.at(100, 30), same.at(100, 30));
  EXPECT_NE(field.at(100, 30), other.at(100, 30));
  EXPECT_EQ(SmoothField({0.f, 0.f}, 7).at(100, 30), Eigen::Vector2f(0, 0));
  EXPECT_THROW(SmoothField({1.f, 0.f}, 7), Error);
}

TEST(DisplaceImage, MovesADotByTheFieldAtItsPosition) {
  const SmoothField field({3.f, 400.f}, 3);  // nearly uniform over the dot's neighbourhood
  const Image img = single_dot(64, 30, 20);
  const Image out = displace_image(img, field, false);
  double mass = 0, cx = 0, cy = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const float a = out.pixel(x, y)[3];
      mass += a, cx += a * (x + 0.5), cy += a * (y + 0.5);
    }
  ASSERT_GT(mass, 0.5);
  const Eigen::Vector2f expected = Eigen::Vector2f(30.5f, 20.5f) + field.at(30.5f, 20.5f);
  EXPECT_GT(field.at(30.5f, 20.5f).norm(), 0.5f);  // the test would not see a field of ~0
  EXPECT_NEAR(cx / mass, expected.x(), 0.25);
  EXPECT_NEAR(cy / mass, expected.y(), 0.25);
}

TEST(BendNormals, TiltsTowardThePicturesRightAndTopByTheFieldsAngle) {
  const SmoothField tilt({5.f, 300.f}, 11);
  Image n = flat_normal_map(32, {0, 0, 1});
  n.pixel(0, 0)[3] = 0;  // background stays untouched
  bend_normals(n, tilt, {1, 0, 0}, {0, 1, 0});
  EXPECT_TRUE(normal_at(n, 0, 0).isApprox(Vec3f(0, 0, 1)));
  for (int p : {5, 17, 28}) {
    const Eigen::Vector2f t = tilt.at(p + 0.5f, p + 0.5f) * 3.14159265f / 180.f;
    const Vec3f bent = normal_at(n, p, p);
    EXPECT_NEAR(bent.x(), std::sin(t.x()), 2e-3f);
    EXPECT_NEAR(bent.y(), std::sin(t.y()), 2e-3f);
  }
}

TEST(ShadeImage, ScalesColourByOnePlusTheFieldAndKeepsAlpha) {
  const SmoothField gain({0.1f, 100.f}, 5);
  Image img = flat_normal_map(16, {0, 0, 0});  // RGB 0.5 everywhere, alpha 1
  shade_image(img, gain);
  EXPECT_NEAR(img.pixel(3, 9)[0], 0.5f * (1 + gain.at(3.5f, 9.5f).x()), 1e-6f);
  EXPECT_EQ(img.pixel(3, 9)[3], 1.f);
}

TEST(PerturbViewSet, SmoothModelsLeaveTheFrontPhotoAndBendEveryNormalMap) {
  fs::path in = fresh_dir("in_smooth"), out = fresh_dir("out_smooth");
  Image photo(32, 32, 4, 0.f);
  for (int y = 4; y < 28; ++y)
    for (int x = 4; x < 28; ++x) {
      float* p = photo.pixel(x, y);
      p[0] = float(x) / 32, p[1] = float(y) / 32, p[2] = 0.5f, p[3] = 1;
    }
  for (const char* view : {"front", "right"}) {
    save_image(photo, in / (std::string(view) + "_rgb.png"));
    save_image(flat_normal_map(32, {0, 0, 1}), in / (std::string(view) + "_normal.png"), 16);
  }
  PerturbOptions o;
  o.displacement = {2.f, 16.f};
  o.bend = {4.f, 32.f};
  o.shading = {0.1f, 32.f};
  o.seed = 3;
  perturb_view_set(in, out, o);
  EXPECT_EQ(load_image_rgba(out / "front_rgb.png").data, load_image_rgba(in / "front_rgb.png").data);
  EXPECT_NE(load_image_rgba(out / "right_rgb.png").data, load_image_rgba(in / "right_rgb.png").data);
  for (const char* view : {"front", "right"})
    EXPECT_NE(load_image_rgba(out / (std::string(view) + "_normal.png")).data,
              load_image_rgba(in / (std::string(view) + "_normal.png")).data)
        << view;
  std::ifstream record(out / "perturbation.json");
  nlohmann::json j = nlohmann::json::parse(record);
  EXPECT_EQ(j["displacement_px"]["amplitude"].get<float>(), 2.f);
  EXPECT_EQ(j["bend_deg"]["scale_px"].get<float>(), 32.f);
  fs::remove_all(in);
  fs::remove_all(out);
}

TEST(PerturbViewSet, MissingOrEmptyFoldersAreErrors) {
  fs::path in = fresh_dir("empty"), out = fresh_dir("out2");
  EXPECT_THROW(perturb_view_set(in / "nope", out, {}), Error);
  EXPECT_THROW(perturb_view_set(in, out, {}), Error);
  EXPECT_THROW(perturb_view_set(in, in, {}), Error);
  fs::remove_all(in);
  fs::remove_all(out);
}
