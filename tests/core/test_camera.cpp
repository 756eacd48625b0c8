#include <gtest/gtest.h>

#include "core/camera.h"

using namespace u3d;

// The four canonical views: front camera on +Z, right on +X, back on -Z, left on -X, +Y up.
TEST(Camera, CanonicalViewsLookFromTheDocumentedSides) {
  struct Case { View v; Eigen::Vector3f toward; Eigen::Vector3f image_right; };
  const Case cases[] = {
      {View::Front, {0, 0, 1}, {1, 0, 0}},
      {View::Right, {1, 0, 0}, {0, 0, -1}},
      {View::Back, {0, 0, -1}, {-1, 0, 0}},
      {View::Left, {-1, 0, 0}, {0, 0, 1}},
  };
  for (const auto& c : cases) {
    Camera cam = view_camera(c.v, 100);
    EXPECT_TRUE(cam.toward_camera().isApprox(c.toward, 1e-6f)) << view_name(c.v);
    // A point on the image-right side of the object lands in the right half of the picture.
    Eigen::Vector3f px = cam.to_pixel(0.5f * c.image_right);
    EXPECT_NEAR(px.x(), 75.f, 1e-3f) << view_name(c.v);
    EXPECT_NEAR(px.y(), 50.f, 1e-3f) << view_name(c.v);
    // +Y is up: a point above the origin is in the upper half (smaller row).
    EXPECT_NEAR(cam.to_pixel({0, 0.5f, 0}).y(), 25.f, 1e-3f) << view_name(c.v);
  }
}

TEST(Camera, PixelMappingCoversMinusOneToOne) {
  Camera cam = view_camera(View::Front, 64);
  Eigen::Vector3f tl = cam.to_pixel({-1, 1, 0});
  Eigen::Vector3f br = cam.to_pixel({1, -1, 0});
  EXPECT_NEAR(tl.x(), 0.f, 1e-4f);
  EXPECT_NEAR(tl.y(), 0.f, 1e-4f);
  EXPECT_NEAR(br.x(), 64.f, 1e-4f);
  EXPECT_NEAR(br.y(), 64.f, 1e-4f);
  // Depth grows away from the camera.
  EXPECT_LT(cam.to_pixel({0, 0, 0.5f}).z(), cam.to_pixel({0, 0, -0.5f}).z());
}

TEST(Camera, PerspectiveProjectsCentreToImageCentre) {
  Camera cam = perspective_camera({0, 0, 3}, 80, 60, 40.f);
  Eigen::Vector3f c = cam.to_pixel({0, 0, 0});
  EXPECT_NEAR(c.x(), 40.f, 1e-4f);
  EXPECT_NEAR(c.y(), 30.f, 1e-4f);
  EXPECT_NEAR(c.z(), 3.f, 1e-5f);
}
