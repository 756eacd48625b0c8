#include <gtest/gtest.h>

#include "core/error.h"
#include "render/render_view.h"
#include "render/supersample.h"
#include "render/texture_sampler.h"
#include "test_meshes.h"

using namespace u3d;

namespace {

constexpr int kRes = 64;

// Pixel of a canonical view seeing image-plane coordinates (u right, v up) in [-1, 1].
std::pair<int, int> view_pixel(float u, float v, int res = kRes) {
  return {int((u + 1.f) * 0.5f * res), int((1.f - v) * 0.5f * res)};
}

Vec4f rgba_at(const Image& im, float u, float v) {
  auto [x, y] = view_pixel(u, v, im.width);
  const float* p = im.pixel(x, y);
  return {p[0], p[1], p[2], p[3]};
}

Vec3f decode_normal(const float* p) { return {2.f * p[0] - 1.f, 2.f * p[1] - 1.f, 2.f * p[2] - 1.f}; }

}  // namespace

// Each view shows the bumps on the side the camera conventions say: front (camera +Z, image right
// +X), right (camera +X, image right -Z), back (camera -Z, image right -X), left (camera -X, image
// right +Z); +Y is up in all of them.
TEST(RenderView, AsymmetricMeshShowsBumpsOnTheExpectedSides) {
  Mesh mesh = test::bumpy_cube();
  struct Case {
    View view;
    float bump_u;  // image-right coordinate where a side bump sticks out
  };
  const Case cases[] = {{View::Front, 0.7f}, {View::Right, -0.65f}, {View::Back, -0.7f}, {View::Left, 0.65f}};
  for (const auto& c : cases) {
    RenderedView r = render_view(mesh, view_camera(c.view, kRes));
    SCOPED_TRACE(view_name(c.view));
    EXPECT_EQ(rgba_at(r.rgb, c.bump_u, 0.f).w(), 1.f);
    EXPECT_EQ(rgba_at(r.rgb, -c.bump_u, 0.f).w(), 0.f);
    EXPECT_EQ(rgba_at(r.rgb, 0.f, 0.6f).w(), 1.f);    // top bump
    EXPECT_EQ(rgba_at(r.rgb, 0.f, -0.6f).w(), 0.f);   // nothing below the cube
    EXPECT_EQ(rgba_at(r.normal, 0.f, -0.6f).w(), 0.f);
    EXPECT_EQ(rgba_at(r.rgb, 0.9f, 0.9f), Vec4f::Zero());  // background is transparent black
    // Untextured, uncoloured: mid-gray.
    EXPECT_TRUE(rgba_at(r.rgb, 0.3f, -0.3f).isApprox(Vec4f(0.5f, 0.5f, 0.5f, 1.f)));
  }
}

TEST(RenderView, NormalColorsInWorldAndCameraSpace) {
  Mesh mesh = test::bumpy_cube();
  // The cube side facing each camera, seen at image point (0.3, -0.3) (away from the bumps).
  const std::pair<View, Vec3f> cases[] = {{View::Front, {0, 0, 1}},
                                          {View::Right, {1, 0, 0}},
                                          {View::Back, {0, 0, -1}},
                                          {View::Left, {-1, 0, 0}}};
  for (const auto& [view, world_normal] : cases) {
    SCOPED_TRACE(view_name(view));
    Camera cam = view_camera(view, kRes);
    RenderedView world = render_view(mesh, cam);
    RenderedView camera = render_view(mesh, cam, RenderSettings{NormalSpace::Camera});
    Vec4f expected_world;
    expected_world << 0.5f * (world_normal + Vec3f::Ones()), 1.f;
    EXPECT_TRUE(rgba_at(world.normal, 0.3f, -0.3f).isApprox(expected_world, 1e-5f)) << rgba_at(world.normal, 0.3f, -0.3f).transpose();
    // Camera space: the facing side points at the viewer, (0, 0, 1) -> (0.5, 0.5, 1).
    EXPECT_TRUE(rgba_at(camera.normal, 0.3f, -0.3f).isApprox(Vec4f(0.5f, 0.5f, 1.f, 1.f), 1e-5f));
  }
}

// From an oblique camera, camera-space normals are the rotated world normals; the +X side (seen on
// the right) points right, the top points up.
TEST(RenderView, CameraSpaceNormalsAreRotatedWorldNormals) {
  Mesh mesh = test::bumpy_cube();
  Camera cam = orthographic_camera(orbit_direction(35.f, 25.f), kRes, kRes);
  RenderedView world = render_view(mesh, cam);
  RenderedView camera = render_view(mesh, cam, RenderSettings{NormalSpace::Camera});
  const Eigen::Matrix3f rot = cam.rotation();
  int checked = 0, right_facing = 0, up_facing = 0;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) {
      if (world.normal.at(x, y, 3) == 0.f) continue;
      Vec3f nw = decode_normal(world.normal.pixel(x, y)), nc = decode_normal(camera.normal.pixel(x, y));
      EXPECT_TRUE(nc.isApprox(rot * nw, 1e-4f));
      EXPECT_GT(nc.z(), 0.f);  // visible sides face the camera
      if (nw.isApprox(Vec3f::UnitX(), 1e-4f)) right_facing += nc.x() > 0.3f;
      if (nw.isApprox(Vec3f::UnitY(), 1e-4f)) up_facing += nc.y() > 0.3f;
      ++checked;
    }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(right_facing, 100);
  EXPECT_GT(up_facing, 100);
}

TEST(RenderView, FlatAndSmoothNormalsAgreeOnABox) {
  Mesh mesh = test::bumpy_cube();
  Camera cam = orthographic_camera(orbit_direction(20.f, 10.f), kRes, kRes);
  RenderedView smooth = render_view(mesh, cam);
  RenderSettings flat_settings;
  flat_settings.smooth_normals = false;
  RenderedView flat = render_view(mesh, cam, flat_settings);
  for (size_t i = 0; i < smooth.normal.data.size(); ++i) ASSERT_NEAR(smooth.normal.data[i], flat.normal.data[i], 1e-5f);
}

namespace {

// The square [-1, 1]^2 at z = 0 as two triangles, UV (0,0) at the bottom-left corner.
Mesh textured_square() {
  Mesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  Material mat;
  mat.texture = Image(2, 2, 3);
  const float texels[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};  // top row red, green; bottom blue, white
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) mat.texture.data[i * 3 + c] = texels[i][c];
  m.materials = {mat};
  return m;
}

}  // namespace

TEST(RenderView, TexturesAppearUprightWithUvOriginBottomLeft) {
  Mesh mesh = textured_square();
  RenderedView r = render_view(mesh, view_camera(View::Front, kRes));
  EXPECT_TRUE(rgba_at(r.rgb, -0.99f, 0.99f).isApprox(Vec4f(1, 0, 0, 1)));   // top-left: red
  EXPECT_TRUE(rgba_at(r.rgb, 0.99f, 0.99f).isApprox(Vec4f(0, 1, 0, 1)));    // top-right: green
  EXPECT_TRUE(rgba_at(r.rgb, -0.99f, -0.99f).isApprox(Vec4f(0, 0, 1, 1)));  // bottom-left: blue
  EXPECT_TRUE(rgba_at(r.rgb, 0.99f, -0.99f).isApprox(Vec4f(1, 1, 1, 1)));   // bottom-right: white
  // Bilinear: the centre is the mean of the four texels.
  const float* centre = r.rgb.pixel(kRes / 2, kRes / 2);
  EXPECT_NEAR(centre[0], 0.5f, 0.02f);
  EXPECT_NEAR(centre[1], 0.5f, 0.02f);
  EXPECT_NEAR(centre[2], 0.5f, 0.02f);
}

TEST(RenderView, BaseColorAndPerFaceMaterials) {
  Mesh mesh = textured_square();
  mesh.materials[0].base_color = Vec4f(0.5f, 1.f, 1.f, 1.f);
  Material blue;
  blue.base_color = Vec4f(0.f, 0.f, 1.f, 1.f);
  mesh.materials.push_back(blue);
  mesh.face_material = {0, 1};  // lower-right triangle textured, upper-left plain blue
  RenderedView r = render_view(mesh, view_camera(View::Front, kRes));
  EXPECT_TRUE(rgba_at(r.rgb, 0.99f, -0.99f).isApprox(Vec4f(0.5f, 1, 1, 1)));  // white texel x base colour
  EXPECT_TRUE(rgba_at(r.rgb, -0.9f, 0.9f).isApprox(Vec4f(0, 0, 1, 1)));
}

TEST(RenderView, VertexColorsAreInterpolated) {
  Mesh mesh;
  mesh.positions = {{-1, -1, 0}, {1, -1, 0}, {-1, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  mesh.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  RenderedView r = render_view(mesh, view_camera(View::Front, kRes));
  EXPECT_TRUE(rgba_at(r.rgb, -0.99f, -0.99f).head<3>().isApprox(Vec3f(1, 0, 0), 0.05f));
  Vec4f mid = rgba_at(r.rgb, -1.f / 3, -1.f / 3);  // centroid
  EXPECT_NEAR(mid.x(), 1.f / 3, 0.03f);
  EXPECT_NEAR(mid.y(), 1.f / 3, 0.03f);
  EXPECT_NEAR(mid.z(), 1.f / 3, 0.03f);
}

// Supersampled edges get fractional alpha but keep the surface colour (no darkening).
TEST(RenderView, SupersamplingGivesFractionalAlphaWithoutDarkening) {
  Mesh mesh;
  // Square whose left edge is at pixel x = 4.5 of a 16-pixel image: pixel 4 is half covered.
  const float left = 4.5f / 8.f - 1.f;
  mesh.positions = {{left, -0.5f, 0}, {0.5f, -0.5f, 0}, {0.5f, 0.5f, 0}, {left, 0.5f, 0}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  mesh.colors.assign(4, Vec3f(0.8f, 0.2f, 0.1f));
  RenderSettings s;
  s.ssaa = 4;
  RenderedView r = render_view(mesh, view_camera(View::Front, 16), s);
  ASSERT_EQ(r.rgb.width, 16);
  const float* edge = r.rgb.pixel(4, 8);
  EXPECT_NEAR(edge[3], 0.5f, 1e-6f);
  EXPECT_NEAR(edge[0], 0.8f, 1e-5f);
  EXPECT_NEAR(edge[1], 0.2f, 1e-5f);
  EXPECT_NEAR(edge[2], 0.1f, 1e-5f);
  EXPECT_EQ(r.rgb.at(3, 8, 3), 0.f);
  EXPECT_EQ(r.rgb.at(5, 8, 3), 1.f);
  EXPECT_NEAR(r.normal.at(4, 8, 2), 1.f, 1e-5f);  // +Z normal keeps its colour too
  EXPECT_NEAR(r.normal.at(4, 8, 3), 0.5f, 1e-6f);
}

TEST(RenderView, RejectsBadSettings) {
  Mesh mesh = test::bumpy_cube();
  RenderSettings s;
  s.ssaa = 0;
  EXPECT_THROW(render_view(mesh, view_camera(View::Front, 8), s), Error);
  EXPECT_THROW(downsample_alpha_weighted(Image(6, 6, 4), 4), Error);
}

TEST(TextureSampler, WrapsOutsideUnitSquareAndClampsInside) {
  Image tex(4, 1, 1);
  tex.data = {0.f, 1.f, 2.f, 3.f};
  EXPECT_NEAR(sample_texture(tex, {0.125f, 0.5f}).x(), 0.f, 1e-6f);  // first texel centre
  EXPECT_NEAR(sample_texture(tex, {0.25f, 0.5f}).x(), 0.5f, 1e-6f);  // between texels 0 and 1
  EXPECT_NEAR(sample_texture(tex, {0.f, 0.5f}).x(), 0.f, 1e-6f);     // border clamps, no wrap-around
  EXPECT_NEAR(sample_texture(tex, {1.f, 0.5f}).x(), 3.f, 1e-6f);
  EXPECT_NEAR(sample_texture(tex, {1.375f, 0.5f}).x(), 1.f, 1e-6f);  // repeats outside [0, 1]
  EXPECT_NEAR(sample_texture(tex, {-0.625f, 0.5f}).x(), 1.f, 1e-6f);
  EXPECT_EQ(sample_texture(tex, {0.3f, 0.5f}).w(), 1.f);
}
