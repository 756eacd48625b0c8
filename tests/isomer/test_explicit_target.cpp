// ExplicitTarget weights against a hand-computed case, and colour completion.
#include <gtest/gtest.h>

#include <cmath>

#include "isomer/color_completion.h"
#include "isomer/explicit_target.h"
#include "isomer/explicit_target_normals.h"
#include "core/synthetic_views.h"

namespace u3d {
namespace {

Image constant_rgba(int size, const Vec3f& rgb, float alpha) {
  Image img(size, size, 4, 0.f);
  for (size_t p = 0; p < img.pixel_count(); ++p) {
    for (int c = 0; c < 3; ++c) img.data[p * 4 + c] = rgb[c];
    img.data[p * 4 + 3] = alpha;
  }
  return img;
}

// A flat square of half-size 0.4 turned by `angle` about +Y: normal (sin a, 0, cos a), facing the
// front and right cameras, seen from behind by the back and left ones.
Mesh tilted_square(float angle) {
  const Vec3f u(std::cos(angle), 0.f, -std::sin(angle)), up(0, 1, 0);
  Mesh m;
  for (float s : {-0.4f, 0.4f})
    for (float t : {-0.4f, 0.4f}) m.positions.push_back(s * u + t * up);
  // vertices: 0 (-u,-up) 1 (-u,+up) 2 (+u,-up) 3 (+u,+up); CCW seen from the normal side
  m.faces = {{0, 2, 1}, {1, 2, 3}};
  return m;
}

TEST(ExplicitTarget, WeightsMatchHandComputedCase) {
  const float angle = float(M_PI) / 6.f;  // 30 degrees: cos^2 = 0.75, sin^2 = 0.25
  const Mesh mesh = tilted_square(angle);
  ASSERT_NEAR(face_normals(mesh.positions, mesh.faces)[0].dot(Vec3f(std::sin(angle), 0, std::cos(angle))), 1.f, 1e-5f);
  const Image front = constant_rgba(64, {1, 0, 0}, 1.f), right = constant_rgba(64, {0, 1, 0}, 0.5f);
  const Image back = constant_rgba(64, {0, 0, 1}, 1.f), left = constant_rgba(64, {0, 0, 1}, 1.f);
  ColorTargetOptions options;
  options.raster_resolution = 64;
  const ExplicitTarget t = compute_explicit_target(mesh, {&front, &right, &back, &left}, options);
  // front: 2.0 * 0.75 * 1 = 1.5; right: 0.2 * 0.25 * 0.5 = 0.025; back and left: not visible.
  const float w_front = 1.5f, w_right = 0.025f;
  for (size_t v = 0; v < 4; ++v) {
    EXPECT_NEAR(t.weight[v], w_front + w_right, 1e-5f) << "vertex " << v;
    const Vec3f mean = t.mean(v);
    EXPECT_NEAR(mean.x(), w_front / (w_front + w_right), 1e-5f);
    EXPECT_NEAR(mean.y(), w_right / (w_front + w_right), 1e-5f);
    EXPECT_NEAR(mean.z(), 0.f, 1e-6f);
  }
  // Linear weighting (the refinement's variant): 2 cos + 0.2 sin * 0.5.
  options.cos_power = 1;
  const ExplicitTarget lin = compute_explicit_target(mesh, {&front, &right, &back, &left}, options);
  EXPECT_NEAR(lin.weight[0], 2.f * std::cos(angle) + 0.1f * std::sin(angle), 1e-5f);
}

// Normals: front and right maps say different things about the tilted square; the fused normal is
// their weighted mean and the disagreement the weighted RMS distance from it, both by hand.
TEST(ExplicitTargetNormals, FusedNormalAndDisagreementMatchHandComputedCase) {
  const float angle = float(M_PI) / 6.f;  // cos 0.866, sin 0.5
  const Mesh mesh = tilted_square(angle);
  const Vec3f a(0, 0, 1), b(1, 0, 0);  // front map says +Z, right map says +X
  auto encoded = [](const Vec3f& n) { return Vec3f((n + Vec3f::Ones()) / 2); };
  std::vector<Image> maps = {constant_rgba(64, encoded(a), 1.f), constant_rgba(64, encoded(b), 1.f),
                             constant_rgba(64, encoded(-a), 1.f), constant_rgba(64, encoded(-b), 1.f)};
  std::vector<Camera> cameras;
  std::vector<RasterBuffer> rasters;
  std::vector<const RasterBuffer*> raster_ptrs;
  for (View v : kAllViews) {
    cameras.push_back(view_camera(v, 64));
    rasters.push_back(rasterize(mesh, cameras.back()));
  }
  for (const RasterBuffer& r : rasters) raster_ptrs.push_back(&r);
  const std::vector<Vec3f> vn = vertex_normals(mesh.positions, mesh.faces);
  const ExplicitTargetNormals t = explicit_target_normals(mesh.positions, mesh.faces, vn, maps, cameras, raster_ptrs);
  // front: 2.0 * cos 30 = 1.732; right: 0.8 * sin 30 = 0.4; back and left see the square from behind.
  const float w1 = 2.f * std::cos(angle), w2 = 0.8f * std::sin(angle), w = w1 + w2;
  const Vec3f mean = (w1 * a + w2 * b) / w;
  for (size_t v = 0; v < 4; ++v) {
    EXPECT_TRUE(t.normals[v].isApprox(mean.normalized(), 1e-4f)) << t.normals[v].transpose();
    // sum w_i |n_i - mean|^2 / w = w1 w2 |a - b|^2 / w^2
    EXPECT_NEAR(t.disagreement[v], std::sqrt(w1 * w2) / w * (a - b).norm(), 1e-3f);
  }
  // Views that agree: no disagreement.
  maps[1] = maps[0];
  const ExplicitTargetNormals same = explicit_target_normals(mesh.positions, mesh.faces, vn, maps, cameras, raster_ptrs);
  for (size_t v = 0; v < 4; ++v) EXPECT_NEAR(same.disagreement[v], 0.f, 1e-3f);
}

TEST(ExplicitTarget, FacesTurnedAwayAreNotVisible) {
  const Mesh mesh = tilted_square(float(M_PI) / 6.f);
  const std::vector<Vec3f> fn = face_normals(mesh.positions, mesh.faces);
  ColorTargetOptions options;
  options.raster_resolution = 64;
  EXPECT_EQ(visible_vertices(mesh, fn, View::Front, options), std::vector<uint8_t>(4, 1));
  EXPECT_EQ(visible_vertices(mesh, fn, View::Back, options), std::vector<uint8_t>(4, 0));
  EXPECT_EQ(visible_vertices(mesh, fn, View::Left, options), std::vector<uint8_t>(4, 0));
}

// A strip of quads along x: columns 0..cols, two vertices per column.
Mesh strip(int cols) {
  Mesh m;
  for (int c = 0; c <= cols; ++c) {
    m.positions.push_back(Vec3f(float(c), 0, 0));
    m.positions.push_back(Vec3f(float(c), 1, 0));
  }
  for (int c = 0; c < cols; ++c) {
    const int a = 2 * c;
    m.faces.push_back({a, a + 2, a + 1});
    m.faces.push_back({a + 1, a + 2, a + 3});
  }
  return m;
}

TEST(ColorCompletion, FillsEverythingWithoutSeamsOrNaN) {
  const int cols = 20;
  Mesh m = strip(cols);
  std::vector<Vec3f> colors(m.positions.size(), Vec3f(0, 0, 0));
  std::vector<uint8_t> known(m.positions.size(), 0);
  for (int k = 0; k < 2; ++k) {  // red at the left end, blue at the right end
    colors[k] = Vec3f(1, 0, 0), known[k] = 1;
    colors[2 * cols + k] = Vec3f(0, 0, 1), known[2 * cols + k] = 1;
  }
  const ColorCompletionReport r = complete_vertex_colors(m.faces, colors, known);
  EXPECT_EQ(r.unreachable, 0u);
  EXPECT_EQ(r.filled, m.positions.size() - 4);
  EXPECT_GT(r.growth_rounds, 0);
  EXPECT_EQ(r.smoothing_rounds, r.growth_rounds);
  float biggest_step = 0.f;
  for (int c = 0; c < cols; ++c) {
    for (int k = 0; k < 2; ++k) ASSERT_TRUE(colors[2 * c + k].allFinite());
    biggest_step = std::max(biggest_step, (colors[2 * c + 2] - colors[2 * c]).norm());
  }
  // Stopping when the two fronts meet would leave a red|blue jump of length sqrt(2) in the middle.
  EXPECT_LT(biggest_step, 0.5f);
  EXPECT_EQ(colors[0], Vec3f(1, 0, 0));  // known colours never change
}

TEST(ColorCompletion, UnreachablePartsKeepTheirFallback) {
  Mesh m = strip(2);
  const int offset = int(m.positions.size());
  for (int k = 0; k < 3; ++k) m.positions.push_back(Vec3f(10.f + k, 0, 0));
  m.faces.push_back({offset, offset + 1, offset + 2});  // an island nobody saw
  std::vector<Vec3f> colors(m.positions.size(), Vec3f(0.5f, 0.5f, 0.5f));
  std::vector<uint8_t> known(m.positions.size(), 0);
  colors[0] = Vec3f(1, 1, 0), known[0] = 1;
  const ColorCompletionReport r = complete_vertex_colors(m.faces, colors, known);
  EXPECT_EQ(r.unreachable, 3u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(colors[offset + k], Vec3f(0.5f, 0.5f, 0.5f));
  for (int v = 1; v < offset; ++v) EXPECT_TRUE(colors[v].isApprox(Vec3f(1, 1, 0)));
}

TEST(Coloring, SphereGetsEveryVertexColoredFromItsViews) {
  // Each view paints its own colour: vertices facing a view take (mostly) that view's colour.
  const std::array<Vec3f, 4> paint = {Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, 0, 1), Vec3f(1, 1, 0)};
  const ViewSet views = testing::sphere_views(0.6f, 128, [&](View v, const Vec3f&) { return paint[size_t(v)]; });
  Mesh mesh;
  for (int i = 0; i < 40; ++i)  // UV sphere
    for (int j = 0; j <= 20; ++j) {
      const float th = float(M_PI) * j / 20, ph = 2 * float(M_PI) * i / 40;
      mesh.positions.push_back(0.6f * Vec3f(std::sin(th) * std::sin(ph), std::cos(th), std::sin(th) * std::cos(ph)));
    }
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 20; ++j) {
      const int a = i * 21 + j, b = ((i + 1) % 40) * 21 + j;
      mesh.faces.push_back({a, a + 1, b});
      mesh.faces.push_back({b, a + 1, b + 1});
    }
  ColoringOptions options;
  options.target.raster_resolution = 256;
  const ColoringReport report = color_mesh(mesh, views, options);
  ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
  for (const Vec3f& c : mesh.colors) ASSERT_TRUE(c.allFinite());
  EXPECT_GT(report.confident, mesh.positions.size() / 2);
  EXPECT_EQ(report.unreachable, 0u);
  // The vertex on the +Z axis (i = 0, j = 10) faces the front view: red.
  EXPECT_TRUE(mesh.colors[10].isApprox(paint[0], 1e-3f)) << mesh.colors[10].transpose();
  // On the +X axis (i = 10): right view, green.
  EXPECT_TRUE(mesh.colors[10 * 21 + 10].isApprox(paint[1], 1e-3f)) << mesh.colors[10 * 21 + 10].transpose();
}

}  // namespace
}  // namespace u3d
