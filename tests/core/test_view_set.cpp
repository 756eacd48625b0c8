// Loading and validating a VIEWS_DIR: conventions, background rules and every rejected input.
#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "synthetic_views.h"

namespace u3d {
namespace {

using testing::fresh_temp_dir;
using testing::sphere_views;
using testing::write_view_set;

// Runs load_view_set and returns the error message ("" if it loaded).
std::string load_error(const std::filesystem::path& dir, NormalSpace space = NormalSpace::World) {
  try {
    load_view_set(dir, space);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ViewSet, RoundTripsASphereInWorldSpace) {
  const ViewSet views = sphere_views(0.6f, 64);
  const auto dir = fresh_temp_dir("roundtrip");
  write_view_set(views, dir);
  const ViewSet loaded = load_view_set(dir);
  EXPECT_EQ(loaded.normal_resolution(), 64);
  // Right view centre pixel sees the point (0.6, 0, 0): world normal +X.
  const Image& n = loaded[View::Right].normals;
  EXPECT_NEAR(n.at(32, 32, 0), 1.f, 0.02f);
  EXPECT_NEAR(n.at(32, 32, 3), 1.f, 0.f);
  EXPECT_EQ(n.at(0, 0, 3), 0.f);
}

TEST(ViewSet, CameraSpaceNormalsAreTurnedToWorld) {
  const auto dir = fresh_temp_dir("camera_space");
  const ViewSet world = sphere_views(0.6f, 64);
  write_view_set(world, dir);
  // Re-encode every normal map in its camera space.
  for (View v : kAllViews) {
    const Eigen::Matrix3f to_cam = view_camera(v, 64).rotation();
    Image img = world[v].normals;
    for (size_t p = 0; p < img.pixel_count(); ++p) {
      const Vec3f c = to_cam * Vec3f(img.data[p * 4], img.data[p * 4 + 1], img.data[p * 4 + 2]);
      for (int k = 0; k < 3; ++k) img.data[p * 4 + k] = 0.5f * (c[k] + 1.f);
    }
    save_image(img, dir / view_file_name(v, true));
  }
  EXPECT_NE(load_error(dir, NormalSpace::World).find("--normal-space"), std::string::npos);
  const ViewSet loaded = load_view_set(dir, NormalSpace::Camera);
  const Image& n = loaded[View::Left].normals;
  EXPECT_NEAR(n.at(32, 32, 0), -1.f, 0.02f);  // left view centre sees the -X pole
}

TEST(ViewSet, MissingAlphaFallsBackToDocumentedRules) {
  const auto dir = fresh_temp_dir("no_alpha");
  const ViewSet views = sphere_views(0.6f, 64);
  write_view_set(views, dir);
  // Front normal map without alpha on a black background, front RGB without alpha too.
  Image normal_rgb(64, 64, 3, 0.f), rgb(64, 64, 3, 1.f);
  for (size_t p = 0; p < normal_rgb.pixel_count(); ++p)
    if (views[View::Front].normals.data[p * 4 + 3] > 0.5f)
      for (int c = 0; c < 3; ++c) normal_rgb.data[p * 3 + c] = 0.5f * (views[View::Front].normals.data[p * 4 + c] + 1.f);
  save_image(normal_rgb, dir / "front_normal.png");
  save_image(rgb, dir / "front_rgb.png");
  const ViewSet loaded = load_view_set(dir);
  size_t differ = 0;
  for (size_t p = 0; p < 64 * 64; ++p) {
    differ += (loaded[View::Front].normals.data[p * 4 + 3] > 0.5f) != (views[View::Front].normals.data[p * 4 + 3] > 0.5f);
    differ += (loaded[View::Front].rgb.data[p * 4 + 3] > 0.5f) != (views[View::Front].normals.data[p * 4 + 3] > 0.5f);
  }
  EXPECT_EQ(differ, 0u);
}

TEST(ViewSet, RejectsBadInputWithClearMessages) {
  const ViewSet good = sphere_views(0.6f, 64);
  auto expect_error = [&](const std::string& name, const std::function<void(const std::filesystem::path&)>& spoil,
                          const std::string& expected) {
    const auto dir = fresh_temp_dir("bad_" + name);
    write_view_set(good, dir);
    spoil(dir);
    const std::string message = load_error(dir);
    EXPECT_NE(message.find(expected), std::string::npos) << name << ": got \"" << message << "\"";
  };
  expect_error("missing", [](auto& d) { std::filesystem::remove(d / "left_normal.png"); }, "lacks left_normal.png");
  expect_error("not_png", [](auto& d) { std::ofstream(d / "back_rgb.png") << "hello"; }, "back_rgb.png: not a PNG file");
  expect_error("size", [&](auto& d) { save_image(resize_image(good[View::Right].rgb, 32, 32), d / "right_rgb.png"); },
               "size mismatch");
  expect_error("not_square", [&](auto& d) { save_image(Image(64, 48, 4, 1.f), d / "front_rgb.png"); }, "must be square");
  expect_error("empty_rgb_mask", [&](auto& d) { save_image(Image(64, 64, 4, 0.f), d / "left_rgb.png"); },
               "left_rgb.png: the mask is empty");
  expect_error("empty_normal_mask", [&](auto& d) {
    Image img = good[View::Back].normals;
    for (size_t p = 0; p < img.pixel_count(); ++p) img.data[p * 4 + 3] = 0.f, img.data[p * 4 + 2] = 1.f;
    save_image(img, d / "back_normal.png");
  }, "mask is empty");
  expect_error("full_mask", [&](auto& d) { save_image(Image(64, 64, 4, 1.f), d / "right_rgb.png"); },
               "covers the whole image");
  expect_error("black_normals", [&](auto& d) {
    Image img(64, 64, 4, 0.f);
    for (size_t p = 0; p < img.pixel_count(); ++p) img.data[p * 4 + 3] = good[View::Front].normals.data[p * 4 + 3];
    save_image(img, d / "front_normal.png");
  }, "all black");
  expect_error("not_normals", [&](auto& d) {
    Image img = good[View::Front].normals;  // foreground painted mid-gray: vectors of length 0
    for (size_t p = 0; p < img.pixel_count(); ++p)
      for (int c = 0; c < 3; ++c) img.data[p * 4 + c] = 0.5f;
    save_image(img, d / "front_normal.png");
  }, "not unit normals");
  expect_error("symlink_loop", [](auto& d) {
    std::filesystem::remove(d / "front_rgb.png");
    std::filesystem::create_symlink(d / "loop_b", d / "loop_a");
    std::filesystem::create_symlink(d / "loop_a", d / "loop_b");
    std::filesystem::create_symlink(d / "loop_a", d / "front_rgb.png");
  }, "front_rgb.png: Too many levels of symbolic links");
  EXPECT_NE(load_error("/nonexistent/views").find("does not exist"), std::string::npos);
  const auto loop = fresh_temp_dir("views_loop");
  std::filesystem::create_symlink(loop / "self", loop / "self");
  EXPECT_NE(load_error(loop / "self").find("Too many levels of symbolic links"), std::string::npos);
}

TEST(ViewSet, RejectsNaN) {
  ViewSet good = sphere_views(0.6f, 32);
  std::array<Image, 4> rgb, normals;
  for (View v : kAllViews) {
    rgb[size_t(v)] = good[v].rgb;
    normals[size_t(v)] = good[v].normals;
  }
  rgb[2].data[100] = std::nanf("");
  EXPECT_THROW(
      {
        try {
          make_view_set(rgb, normals, NormalSpace::World, {"f", "r", "b", "l"}, {"fn", "rn", "bn", "ln"});
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("b: contains NaN"), std::string::npos) << e.what();
          throw;
        }
      },
      Error);
}

}  // namespace
}  // namespace u3d
