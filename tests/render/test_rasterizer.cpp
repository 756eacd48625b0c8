#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/error.h"
#include "render/rasterizer.h"

using namespace u3d;

namespace {

// Front view of the z = 0 plane: pixel (px, py) <-> world ((px / res) * 2 - 1, 1 - (py / res) * 2).
Vec3f pixel_to_world(float px, float py, int res) { return {px / res * 2.f - 1.f, 1.f - py / res * 2.f, 0.f}; }

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
}

// Per pixel, how many of the triangles (each rasterized alone) cover it.
std::vector<int> coverage_counts(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                                 const Camera& cam) {
  std::vector<int> counts(size_t(cam.width) * cam.height, 0);
  for (const auto& f : faces) {
    RasterBuffer buf = rasterize(positions, {f}, cam);
    for (size_t i = 0; i < buf.pixel_count(); ++i) counts[i] += buf.covered(i);
  }
  return counts;
}

}  // namespace

TEST(Rasterizer, EmptyMeshGivesBackground) {
  RasterBuffer buf = rasterize(std::vector<Vec3f>{}, std::vector<Vec3i>{}, view_camera(View::Front, 8));
  ASSERT_EQ(buf.pixel_count(), 64u);
  for (size_t i = 0; i < buf.pixel_count(); ++i) {
    EXPECT_EQ(buf.face_id[i], -1);
    EXPECT_TRUE(std::isinf(buf.depth[i]));
  }
}

TEST(Rasterizer, RejectsBadIndices) {
  std::vector<Vec3f> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(rasterize(p, {Vec3i(0, 1, 3)}, view_camera(View::Front, 8)), Error);
  EXPECT_THROW(rasterize(p, {Vec3i(-1, 1, 2)}, view_camera(View::Front, 8)), Error);
}

// Faces touching a NaN or infinite vertex are dropped; the rest of the mesh still renders.
TEST(Rasterizer, FacesWithNonFiniteVerticesAreDropped) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  std::vector<Vec3f> p = {{-0.9f, -0.9f, 0}, {0.9f, -0.9f, 0}, {-0.9f, 0.9f, 0}, {nan, 0.5f, 0}, {0.5f, inf, 0}};
  std::vector<Vec3i> f = {{0, 3, 2}, {0, 1, 2}, {1, 4, 2}};
  RasterBuffer buf = rasterize(p, f, view_camera(View::Front, 32));
  int covered = 0;
  for (size_t i = 0; i < buf.pixel_count(); ++i) {
    if (!buf.covered(i)) continue;
    ++covered;
    EXPECT_EQ(buf.face_id[i], 1);
  }
  EXPECT_GT(covered, 300);
}

// Pixels whose centre is clearly inside a triangle are covered and clearly outside are not ("clearly":
// farther than the 1/256-pixel vertex snapping can move an edge); for triangles inside the image the
// covered count matches the analytic area within the perimeter.
TEST(Rasterizer, CoverageMatchesGeometryForRandomTriangles) {
  const int res = 96;
  Camera cam = view_camera(View::Front, res);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> inside_coord(1.f, res - 1.f), any_coord(-30.f, res + 30.f);
  for (int trial = 0; trial < 400; ++trial) {
    const bool leaves_image = trial % 2 == 1;
    Eigen::Vector2d v[3];
    std::vector<Vec3f> p(3);
    for (int k = 0; k < 3; ++k) {
      float px = leaves_image ? any_coord(rng) : inside_coord(rng), py = leaves_image ? any_coord(rng) : inside_coord(rng);
      p[k] = pixel_to_world(px, py, res);
      v[k] = Eigen::Vector2d(px, py);
    }
    RasterBuffer buf = rasterize(p, {Vec3i(0, 1, 2)}, cam);
    double area2 = cross2(v[0], v[1], v[2]);
    double s = area2 > 0 ? 1 : -1;
    int clear_mismatches = 0;
    long covered = 0;
    for (int y = 0; y < res; ++y)
      for (int x = 0; x < res; ++x) {
        Eigen::Vector2d c(x + 0.5, y + 0.5);
        double margin = 1e30;
        bool inside = true;
        for (int k = 0; k < 3; ++k) {
          const auto& a = v[k];
          const auto& b = v[(k + 1) % 3];
          double e = s * cross2(a, b, c) / (b - a).norm();  // signed distance, positive inside
          margin = std::min(margin, std::abs(e));
          inside = inside && e > 0;
        }
        bool got = buf.covered(size_t(y) * res + x);
        covered += got;
        if (margin > 0.01 && got != inside) ++clear_mismatches;
      }
    EXPECT_EQ(clear_mismatches, 0) << "trial " << trial;
    if (!leaves_image) {
      double perimeter = (v[1] - v[0]).norm() + (v[2] - v[1]).norm() + (v[0] - v[2]).norm();
      EXPECT_NEAR(double(covered), 0.5 * std::abs(area2), 0.5 * perimeter + 1) << "trial " << trial;
    }
  }
}

// n x n square cells of `cell` px starting at pixel 4, cut along alternating diagonals. Border vertices
// sit at pixel centres; interior ones move by `shift` + half a pixel times a random integer in
// [-max_jitter, max_jitter], so vertices and edges often pass exactly through pixel centres.
struct Grid {
  std::vector<Vec3f> positions;
  std::vector<Vec3i> faces;
};
Grid jittered_grid(int res, int n, float cell, float shift, int max_jitter, std::mt19937& rng) {
  std::uniform_int_distribution<int> jitter(-max_jitter, max_jitter);
  Grid g;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      bool border = i == 0 || j == 0 || i == n || j == n;
      float px = 4.f + cell * i + (border ? 0.5f : shift + 0.5f * jitter(rng));
      float py = 4.f + cell * j + (border ? 0.5f : shift + 0.5f * jitter(rng));
      g.positions.push_back(pixel_to_world(px, py, res));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      if ((i + j) % 2) {
        g.faces.push_back({a, c, b});
        g.faces.push_back({b, c, d});
      } else {
        g.faces.push_back({a, c, d});
        g.faces.push_back({a, d, b});
      }
    }
  return g;
}

// Jittered 8 px cells: every pixel of the square is covered exactly once, none outside it.
TEST(Rasterizer, SharedEdgesCoverEachPixelExactlyOnce) {
  const int res = 40;
  Camera cam = view_camera(View::Front, res);
  std::mt19937 rng(3);
  const Grid grid = jittered_grid(res, 4, 8.f, 0.f, 3, rng);  // 4 x 4 cells from pixel 4 to 36
  std::vector<int> counts = coverage_counts(grid.positions, grid.faces, cam);
  RasterBuffer all = rasterize(grid.positions, grid.faces, cam);
  for (int y = 0; y < res; ++y)
    for (int x = 0; x < res; ++x) {
      // The square spans pixel coordinates [4.5, 36.5]: centres 5.5 .. 35.5 are inside, 4.5 and 36.5
      // lie on its boundary and belong to it only on the top/left sides.
      bool inside = x >= 4 && x <= 35 && y >= 4 && y <= 35;
      EXPECT_EQ(counts[size_t(y) * res + x], inside ? 1 : 0) << x << "," << y;
      EXPECT_EQ(all.covered(size_t(y) * res + x), inside) << x << "," << y;
    }
}

// The same with cells of 3 px (triangles small enough for the rasterizer's SSE2 block path), across a
// tile border (x = 32).
TEST(Rasterizer, SmallSharedEdgeTrianglesCoverEachPixelExactlyOnce) {
  const int res = 48;
  Camera cam = view_camera(View::Front, res);
  std::mt19937 rng(11);
  const Grid grid = jittered_grid(res, 12, 3.f, 0.5f, 1, rng);  // 12 x 12 cells from pixel 4 to 40
  const std::vector<int> counts = coverage_counts(grid.positions, grid.faces, cam);
  for (int y = 0; y < res; ++y)
    for (int x = 0; x < res; ++x) {
      // The square spans pixel coordinates [4.5, 40.5]: the centres on its left and top sides belong to it.
      bool inside = x >= 4 && x <= 39 && y >= 4 && y <= 39;
      EXPECT_EQ(counts[size_t(y) * res + x], inside ? 1 : 0) << x << "," << y;
    }
}

// Small random triangles (at most 4 or 8 px across, the rasterizer's one- and two-vector blocks; some
// on tile borders): coverage agrees with the geometry wherever the centre is clearly inside or
// outside, and barycentrics reproject to the pixel centre.
TEST(Rasterizer, SmallTrianglesMatchGeometry) {
  const int res = 64;
  Camera cam = view_camera(View::Front, res);
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> corner(2.f, res - 10.f), unit(0.f, 1.f);
  for (int trial = 0; trial < 2000; ++trial) {
    const float size = trial % 2 == 0 ? 4.f : 8.f;
    const float cx = trial % 4 < 2 ? 32.f - size * unit(rng) : corner(rng), cy = corner(rng);  // some straddle x = 32
    Eigen::Vector2d v[3];
    std::vector<Vec3f> p(3);
    for (int k = 0; k < 3; ++k) {
      v[k] = Eigen::Vector2d(cx + size * unit(rng), cy + size * unit(rng));
      p[k] = pixel_to_world(float(v[k].x()), float(v[k].y()), res);
    }
    const RasterBuffer buf = rasterize(p, {Vec3i(0, 1, 2)}, cam);
    const double s = cross2(v[0], v[1], v[2]) > 0 ? 1 : -1;
    for (int y = 0; y < res; ++y)
      for (int x = 0; x < res; ++x) {
        const Eigen::Vector2d c(x + 0.5, y + 0.5);
        double margin = 1e30;
        bool inside = true;
        for (int k = 0; k < 3; ++k) {
          const auto& a = v[k];
          const auto& b = v[(k + 1) % 3];
          const double e = s * cross2(a, b, c) / (b - a).norm();
          margin = std::min(margin, std::abs(e));
          inside = inside && e > 0;
        }
        const size_t i = size_t(y) * res + x;
        if (margin > 0.01) {
          ASSERT_EQ(buf.covered(i), inside) << "trial " << trial << " pixel " << x << "," << y;
        }
        if (!buf.covered(i)) continue;
        const float b1 = buf.bary[i].x(), b2 = buf.bary[i].y();
        const Eigen::Vector2d q = (1.0 - b1 - b2) * v[0] + double(b1) * v[1] + double(b2) * v[2];
        ASSERT_LT((q - c).norm(), 0.02) << "trial " << trial << " pixel " << x << "," << y;
      }
  }
}

// Fan of 8 triangles around a vertex on a pixel centre, spokes along axes and diagonals (edges through
// many pixel centres), seen from the front (front faces) and from the back (back faces).
TEST(Rasterizer, FanAroundVertexCoversEachPixelExactlyOnce) {
  const int res = 32;
  std::vector<Vec3f> p = {pixel_to_world(16.5f, 16.5f, res)};
  const float ring[8][2] = {{26.5f, 16.5f}, {26.5f, 6.5f}, {16.5f, 6.5f}, {6.5f, 6.5f},
                            {6.5f, 16.5f},  {6.5f, 26.5f}, {16.5f, 26.5f}, {26.5f, 26.5f}};
  for (const auto& r : ring) p.push_back(pixel_to_world(r[0], r[1], res));
  std::vector<Vec3i> f;
  for (int k = 0; k < 8; ++k) f.push_back({0, 1 + k, 1 + (k + 1) % 8});  // CCW seen from +Z
  for (View view : {View::Front, View::Back}) {
    Camera cam = view_camera(view, res);
    std::vector<int> counts = coverage_counts(p, f, cam);
    for (int y = 0; y < res; ++y)
      for (int x = 0; x < res; ++x) {
        // The back view mirrors x: pixel x sees world pixel column res - 1 - x.
        int wx = view == View::Front ? x : res - 1 - x;
        // Square [6.5, 26.5]^2: centres 6.5 are on the top/left boundary in the front view.
        int lo = view == View::Front ? 6 : 7, hi = view == View::Front ? 25 : 26;
        bool inside = wx >= lo && wx <= hi && y >= 6 && y <= 25;
        EXPECT_EQ(counts[size_t(y) * res + x], inside ? 1 : 0) << view_name(view) << " " << x << "," << y;
      }
  }
}

TEST(Rasterizer, NearerTriangleWinsRegardlessOfOrderAndTiesGoToLowerId) {
  Camera cam = view_camera(View::Front, 32);
  // Two overlapping squares: A at z = +0.3 (nearer to the +Z camera), B at z = -0.3, shifted.
  auto square = [](float x0, float y0, float x1, float y1, float z, std::vector<Vec3f>& p, std::vector<Vec3i>& f) {
    int b = int(p.size());
    p.insert(p.end(), {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}});
    f.push_back({b, b + 1, b + 2});
    f.push_back({b, b + 2, b + 3});
  };
  for (int order = 0; order < 2; ++order) {
    std::vector<Vec3f> p;
    std::vector<Vec3i> f;
    if (order == 0) {
      square(-0.8f, -0.8f, 0.4f, 0.4f, 0.3f, p, f);
      square(-0.4f, -0.4f, 0.8f, 0.8f, -0.3f, p, f);
    } else {
      square(-0.4f, -0.4f, 0.8f, 0.8f, -0.3f, p, f);
      square(-0.8f, -0.8f, 0.4f, 0.4f, 0.3f, p, f);
    }
    RasterBuffer buf = rasterize(p, f, cam);
    // Pixel at world (0, 0): inside both; A must win.
    size_t centre = size_t(16) * 32 + 16;
    int a_first = order == 0 ? 0 : 2;
    EXPECT_TRUE(buf.face_id[centre] == a_first || buf.face_id[centre] == a_first + 1);
    EXPECT_NEAR(buf.depth[centre], 10.f - 0.3f, 1e-4f);
    // Pixel at world (0.6, 0.6): only B.
    size_t b_only = size_t(4) * 32 + 28;
    int b_first = order == 0 ? 2 : 0;
    EXPECT_TRUE(buf.face_id[b_only] == b_first || buf.face_id[b_only] == b_first + 1);
    EXPECT_NEAR(buf.depth[b_only], 10.f + 0.3f, 1e-4f);
  }
  // Coplanar overlap: the lower face id owns the shared pixels, whichever triangle it is.
  std::vector<Vec3f> p = {{-0.9f, -0.9f, 0}, {0.9f, -0.9f, 0}, {-0.9f, 0.9f, 0}, {0.9f, 0.9f, 0}};
  std::vector<Vec3i> f1 = {{0, 1, 2}, {1, 3, 2}, {0, 1, 3}};  // face 2 overlaps both
  std::vector<Vec3i> f2 = {{0, 1, 3}, {0, 1, 2}, {1, 3, 2}};
  RasterBuffer b1 = rasterize(p, f1, cam), b2 = rasterize(p, f2, cam);
  size_t lower_right = size_t(24) * 32 + 20;  // inside {0,1,2} and {0,1,3}
  EXPECT_EQ(b1.face_id[lower_right], 0);
  EXPECT_EQ(b2.face_id[lower_right], 0);
  size_t upper_right = size_t(6) * 32 + 28;  // inside {1,3,2} and {0,1,3}
  EXPECT_EQ(b1.face_id[upper_right], 1);
  EXPECT_EQ(b2.face_id[upper_right], 0);
}

// Perspective-correct barycentrics give back the 3D point seen at each pixel centre.
TEST(Rasterizer, BarycentricsReprojectToPixelCentres) {
  std::vector<Vec3f> p = {{-1.2f, -0.9f, -2.5f}, {1.1f, -0.7f, 0.8f}, {0.1f, 1.0f, -0.4f}};
  for (bool ortho : {false, true}) {
    Camera cam = ortho ? orthographic_camera(Vec3f(0.3f, 0.2f, 1.f), 64, 48, 1.5f)
                       : perspective_camera({0.4f, 0.3f, 3.f}, 64, 48, 50.f);
    RasterBuffer buf = rasterize(p, {Vec3i(0, 1, 2)}, cam);
    int covered = 0;
    for (int y = 0; y < buf.height; ++y)
      for (int x = 0; x < buf.width; ++x) {
        size_t i = size_t(y) * buf.width + x;
        if (!buf.covered(i)) continue;
        ++covered;
        Vec2f b = buf.bary[i];
        EXPECT_GE(b.x(), -1e-5f);
        EXPECT_GE(b.y(), -1e-5f);
        EXPECT_LE(b.x() + b.y(), 1.f + 1e-5f);
        Vec3f q = (1 - b.x() - b.y()) * p[0] + b.x() * p[1] + b.y() * p[2];
        Eigen::Vector3f px = cam.to_pixel(q);
        EXPECT_NEAR(px.x(), x + 0.5f, 2e-3f) << (ortho ? "ortho " : "persp ") << x << "," << y;
        EXPECT_NEAR(px.y(), y + 0.5f, 2e-3f) << (ortho ? "ortho " : "persp ") << x << "," << y;
        EXPECT_NEAR(buf.depth[i], px.z(), 1e-4f * px.z());
      }
    EXPECT_GT(covered, 150);
  }
}

// A floor triangle passing behind a perspective camera is clipped at the near plane: the image
// below the horizon is covered, above it is not, and the barycentrics still reproject.
TEST(Rasterizer, TrianglesCrossingTheNearPlaneAreClipped) {
  const int res = 64;
  Camera cam = perspective_camera({0, 0, 3}, res, res, 60.f, 0.1f, 100.f);
  std::vector<Vec3f> p = {{-300.f, -1.f, 60.f}, {300.f, -1.f, 60.f}, {0.f, -1.f, -60.f}};
  RasterBuffer buf = rasterize(p, {Vec3i(0, 1, 2)}, cam);
  for (int y = 0; y < res; ++y)
    for (int x = 0; x < res; ++x) {
      size_t i = size_t(y) * res + x;
      if (y >= res / 2 + 2) {
        EXPECT_TRUE(buf.covered(i)) << x << "," << y;
      }
      if (y < res / 2) {
        EXPECT_FALSE(buf.covered(i)) << x << "," << y;
      }
      if (!buf.covered(i)) continue;
      Vec2f b = buf.bary[i];
      Vec3f q = (1 - b.x() - b.y()) * p[0] + b.x() * p[1] + b.y() * p[2];
      EXPECT_NEAR(q.y(), -1.f, 1e-3f);
      Eigen::Vector3f px = cam.to_pixel(q);
      EXPECT_NEAR(px.x(), x + 0.5f, 0.01f) << x << "," << y;
      EXPECT_NEAR(px.y(), y + 0.5f, 0.01f) << x << "," << y;
    }
}

TEST(Rasterizer, BackfaceCullingDropsFacesPointingAway) {
  std::vector<Vec3f> p = {{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0, 0.5f, 0}};  // CCW from +Z
  std::vector<Vec3i> f = {{0, 1, 2}};
  auto count = [&](View v, bool cull) {
    RasterBuffer buf = rasterize(p, f, view_camera(v, 32), RasterOptions{cull});
    int n = 0;
    for (size_t i = 0; i < buf.pixel_count(); ++i) n += buf.covered(i);
    return n;
  };
  EXPECT_GT(count(View::Front, true), 50);
  EXPECT_EQ(count(View::Front, true), count(View::Front, false));
  EXPECT_EQ(count(View::Back, true), 0);
  EXPECT_EQ(count(View::Back, false), count(View::Front, false));
}

// Large enough that every stage runs in parallel; clipped triangles included (some cross the near plane).
TEST(Rasterizer, ResultDoesNotDependOnThreadCount) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> centre(-1.5f, 1.5f), offset(-0.15f, 0.15f);
  std::vector<Vec3f> p;
  std::vector<Vec3i> f;
  for (int t = 0; t < 30000; ++t) {
    Vec3f c(centre(rng), centre(rng), centre(rng));
    int b = int(p.size());
    for (int k = 0; k < 3; ++k) p.push_back(c + Vec3f(offset(rng), offset(rng), offset(rng)));
    f.push_back({b, b + 1, b + 2});
  }
  Camera cam = perspective_camera({0.5f, 0.5f, 1.6f}, 300, 200, 60.f, 0.3f);
  int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  RasterBuffer one = rasterize(p, f, cam);
  omp_set_num_threads(std::max(saved, 3));
  RasterBuffer many = rasterize(p, f, cam);
  omp_set_num_threads(saved);
  EXPECT_EQ(one.face_id, many.face_id);
  EXPECT_EQ(one.depth, many.depth);
  EXPECT_EQ(one.bary, many.bary);
}

// Watertightness at scale (parallel path): a jittered 120 x 120 grid whose quads are split along the
// same diagonal. Its triangles form two classes (lower-right, upper-left) that only meet along
// edges, so rendering each class alone must cover disjoint pixel sets whose union is the whole square.
TEST(Rasterizer, LargeGridIsWatertightWithoutDoubleCoverage) {
  const int res = 512, n = 120, cell = 4, origin = 16;
  Camera cam = view_camera(View::Front, res);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> jitter(-2, 2);
  std::vector<Vec3f> p;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      bool border = i == 0 || j == 0 || i == n || j == n;
      float px = origin + cell * i + (border ? 0.f : 0.5f * jitter(rng));
      float py = origin + cell * j + (border ? 0.f : 0.5f * jitter(rng));
      p.push_back(pixel_to_world(px, py, res));
    }
  std::vector<Vec3i> lower, upper, all;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;  // a top-left, d bottom-right
      lower.push_back({c, d, b});
      upper.push_back({a, c, b});
    }
  all = lower;
  all.insert(all.end(), upper.begin(), upper.end());
  RasterBuffer l = rasterize(p, lower, cam), u = rasterize(p, upper, cam), both = rasterize(p, all, cam);
  long double_covered = 0, holes = 0, mismatched = 0;
  for (int y = 0; y < res; ++y)
    for (int x = 0; x < res; ++x) {
      size_t i = size_t(y) * res + x;
      // The square spans pixel coordinates [16, 496]: centres 16.5 .. 495.5 are inside.
      bool inside = x >= origin && x < origin + n * cell && y >= origin && y < origin + n * cell;
      double_covered += l.covered(i) && u.covered(i);
      holes += inside && !(l.covered(i) || u.covered(i));
      mismatched += both.covered(i) != inside;
    }
  EXPECT_EQ(double_covered, 0);
  EXPECT_EQ(holes, 0);
  EXPECT_EQ(mismatched, 0);
}

// Frame-by-frame reuse: after the mesh moves (and shrinks, and leaves the image), rasterize_into into
// the old buffer equals a fresh rasterization, and the footprint bounds every covered pixel.
TEST(Rasterizer, ReusedBufferEqualsFreshRasterization) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  const Camera cam = view_camera(View::Front, 96);
  RasterBuffer reused;
  for (int frame = 0; frame < 6; ++frame) {
    const float scale = frame == 4 ? 0.f : 1.f / float(1 + frame);  // frame 4: nothing on screen
    std::vector<Vec3f> p;
    std::vector<Vec3i> f;
    for (int t = 0; t < 40; ++t) {
      for (int k = 0; k < 3; ++k) p.push_back(frame == 4 ? Vec3f(5.f, 5.f, 0.f) : Vec3f(u(rng), u(rng), u(rng)) * scale);
      f.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    rasterize_into(p, f, cam, reused);
    const RasterBuffer fresh = rasterize(p, f, cam);
    ASSERT_EQ(reused.face_id, fresh.face_id) << "frame " << frame;
    ASSERT_EQ(reused.depth, fresh.depth) << "frame " << frame;
    for (size_t i = 0; i < fresh.pixel_count(); ++i) {
      ASSERT_EQ(reused.bary[i], fresh.bary[i]) << "frame " << frame << " pixel " << i;
      if (!fresh.covered(i)) continue;
      const int x = int(i % 96), y = int(i / 96);
      ASSERT_TRUE(x >= fresh.footprint.x0 && x <= fresh.footprint.x1 && y >= fresh.footprint.y0 &&
                  y <= fresh.footprint.y1)
          << "frame " << frame << " pixel " << i;
    }
    EXPECT_EQ(fresh.footprint.empty(), frame == 4);
  }
}
