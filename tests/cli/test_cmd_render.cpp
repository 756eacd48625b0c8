#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include "core/image.h"
#include "geometry/test_shapes.h"
#include "io/mesh_io.h"
#include "render/render_view.h"
#include "render/test_meshes.h"

using namespace u3d;
namespace fs = std::filesystem;

namespace {

struct RenderCliTest : ::testing::Test {
  fs::path dir;
  void SetUp() override {
    dir = fs::temp_directory_path() / ("u3d_render_cli_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  int run(const std::string& args) {
    std::string cmd = std::string(UNIQUE3D_CLI) + " --quiet render " + args + " > " + (dir / "log.txt").string() + " 2>&1";
    return WEXITSTATUS(std::system(cmd.c_str()));
  }
  std::string log() const {
    FILE* f = std::fopen((dir / "log.txt").c_str(), "r");
    std::string s;
    if (!f) return s;
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
    std::fclose(f);
    return s;
  }
};

float max_abs_difference(const Image& a, const Image& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.channels, b.channels);
  float d = 0;
  for (size_t i = 0; i < std::min(a.data.size(), b.data.size()); ++i) d = std::max(d, std::abs(a.data[i] - b.data[i]));
  return d;
}

}  // namespace

// The CLI writes the four views and turntable images, identical (up to 8-bit rounding) to
// render_view of the normalized mesh.
TEST_F(RenderCliTest, WritesFourViewsMatchingRenderView) {
  Mesh mesh = test::bumpy_cube();
  write_mesh(mesh, dir / "cube.obj");
  ASSERT_EQ(run((dir / "cube.obj").string() + " -o " + (dir / "out").string() + " --res 48 --turntable 3"), 0) << log();
  normalize_to_unit_box(mesh, 0.9f);
  RenderSettings settings;
  settings.ssaa = 2;
  for (View v : kAllViews) {
    RenderedView expected = render_view(mesh, view_camera(v, 48), settings);
    Image rgb = load_image_rgba(dir / "out" / (std::string(view_name(v)) + "_rgb.png"));
    Image normal = load_image_rgba(dir / "out" / (std::string(view_name(v)) + "_normal.png"));
    EXPECT_LE(max_abs_difference(rgb, expected.rgb), 0.5f / 255 + 1e-6f) << view_name(v);
    EXPECT_LE(max_abs_difference(normal, expected.normal), 0.5f / 255 + 1e-6f) << view_name(v);
  }
  for (const char* name : {"turntable_000.png", "turntable_001.png", "turntable_002.png"})
    EXPECT_TRUE(fs::exists(dir / "out" / name)) << name;
  EXPECT_FALSE(fs::exists(dir / "out" / "turntable_003.png"));
}

// At elevation 0 a turntable of four frames passes through the four views: frame 0 is the front view and
// frame 2 the back one, frames 1 and 3 the right and left ones (in the turntable's direction of turn), each
// the very image the views got.
TEST_F(RenderCliTest, FourFrameTurntableAtElevationZeroIsTheFourViews) {
  write_mesh(test::bumpy_cube(), dir / "cube.obj");
  ASSERT_EQ(run((dir / "cube.obj").string() + " -o " + (dir / "out").string() + " --res 48 --turntable 4 --elevation 0"),
            0)
      << log();
  auto load = [&](const std::string& name) { return load_image_rgba(dir / "out" / name); };
  auto same = [&](const Image& a, const Image& b) { return max_abs_difference(a, b) <= 1.f / 255 + 1e-6f; };
  EXPECT_TRUE(same(load("turntable_000.png"), load("front_rgb.png")));
  EXPECT_TRUE(same(load("turntable_002.png"), load("back_rgb.png")));
  EXPECT_FALSE(same(load("right_rgb.png"), load("left_rgb.png")));  // the cube's bumps tell them apart
  const Image first = load("turntable_001.png"), third = load("turntable_003.png");
  EXPECT_TRUE((same(first, load("right_rgb.png")) && same(third, load("left_rgb.png"))) ||
              (same(first, load("left_rgb.png")) && same(third, load("right_rgb.png"))));
}

// Against closed forms, not the renderer: a sphere scaled to fill 0.9 (radius 0.9 of the views' half
// width 1) covers pi 0.9^2 / 4 = 63.6 % of each view, and faces each camera at the image centre.
TEST_F(RenderCliTest, SphereCoversItsAnalyticAreaInEveryView) {
  write_mesh(test::sphere_mesh(1.f, 5), dir / "sphere.ply");  // 20480 faces: 0.05 % less area than the sphere
  ASSERT_EQ(run((dir / "sphere.ply").string() + " -o " + (dir / "out").string() + " --res 128"), 0) << log();
  const double expected = 3.14159265 * 0.9 * 0.9 / 4;
  for (View v : kAllViews) {
    const Image rgb = load_image_rgba(dir / "out" / (std::string(view_name(v)) + "_rgb.png"));
    double covered = 0;
    for (size_t p = 0; p < rgb.pixel_count(); ++p) covered += rgb.data[p * 4 + 3];
    // Anti-aliased edges (--ssaa 2) quantised to 8 bits: the area is good to about 0.2 %.
    EXPECT_NEAR(covered / double(rgb.pixel_count()), expected, 0.004) << view_name(v);
    const Image normal = load_image_rgba(dir / "out" / (std::string(view_name(v)) + "_normal.png"));
    const Vec3f toward = view_camera(v, 128).toward_camera();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(normal.at(64, 64, c), 0.5f * (toward[c] + 1), 0.02f) << view_name(v);
  }
}

TEST_F(RenderCliTest, CameraSpaceNormalsWithoutNormalization) {
  write_mesh(test::bumpy_cube(), dir / "cube.ply");
  ASSERT_EQ(run((dir / "cube.ply").string() + " -o " + (dir / "out").string() +
                " --res 32 --ssaa 1 --normal-space camera --no-normalize"),
            0)
      << log();
  // Without normalization the cube keeps its size: the side facing each camera covers image
  // point (0.3, -0.3), pixel (20, 20) of 32, and its camera-space normal is (0, 0, 1).
  for (View v : kAllViews) {
    Image normal = load_image_rgba(dir / "out" / (std::string(view_name(v)) + "_normal.png"));
    EXPECT_NEAR(normal.at(20, 20, 0), 0.5f, 1.f / 255) << view_name(v);
    EXPECT_NEAR(normal.at(20, 20, 1), 0.5f, 1.f / 255) << view_name(v);
    EXPECT_NEAR(normal.at(20, 20, 2), 1.f, 1.f / 255) << view_name(v);
    EXPECT_EQ(normal.at(20, 28, 3), 0.f) << view_name(v);  // below the cube (y = -0.78)
  }
}

TEST_F(RenderCliTest, MissingMeshIsAClearError) {
  EXPECT_EQ(run((dir / "nope.obj").string() + " -o " + (dir / "out").string()), 1);
  EXPECT_NE(log().find("nope.obj"), std::string::npos) << log();
}

TEST_F(RenderCliTest, RejectsBadOptions) {
  write_mesh(test::bumpy_cube(), dir / "cube.obj");
  EXPECT_NE(run((dir / "cube.obj").string() + " -o " + (dir / "out").string() + " --normal-space tangent"), 0);
  EXPECT_NE(run((dir / "cube.obj").string() + " -o " + (dir / "out").string() + " --res 0"), 0);
  EXPECT_EQ(run((dir / "cube.obj").string() + " -o " + (dir / "out").string() + " --res 4096 --ssaa 4"), 1);
  EXPECT_NE(log().find("8192"), std::string::npos) << log();
  // NaN passes CLI11's own range checks (every comparison with it is false).
  for (const char* bad : {"--elevation nan", "--elevation inf", "--fill nan", "--fill 2"}) {
    EXPECT_NE(run((dir / "cube.obj").string() + " -o " + (dir / "out").string() + " --turntable 2 " + bad), 0) << bad;
    const std::string message = log();
    EXPECT_TRUE(message.find("is not in [") != std::string::npos) << bad << ": " << message;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}
