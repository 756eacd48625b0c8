// Perturbation of view sets: warps move pixels where geometry says, normals turn with the picture,
// noise is deterministic, and the folder-level command handles partial and bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
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
  fs::path d = fs::temp_directory_path() / ("u3d_test_perturb_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
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

TEST(PerturbViewSet, MissingOrEmptyFoldersAreErrors) {
  fs::path in = fresh_dir("empty"), out = fresh_dir("out2");
  EXPECT_THROW(perturb_view_set(in / "nope", out, {}), Error);
  EXPECT_THROW(perturb_view_set(in, out, {}), Error);
  EXPECT_THROW(perturb_view_set(in, in, {}), Error);
  fs::remove_all(in);
  fs::remove_all(out);
}
