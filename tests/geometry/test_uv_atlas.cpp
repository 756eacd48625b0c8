// Axis-projected chart atlas: UVs inside the atlas, every face counter-clockwise, no texel claimed by
// two faces (also on a helicoid, whose charts fold over themselves), no texel touched by two charts
// and a gutter of empty texels between charts (also at 2048, packed on 2 x 2 texel cells), the same
// texel density in every chart, the texels used on a sphere and on a T-shaped body (whose front chart
// must be cut to pack; the axis charts with shelf packing used 35-45 % on the sphere), and the
// geometry unchanged but for the seam copies.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "geometry/icosphere.h"
#include "geometry/marching_tetrahedra.h"
#include "geometry/mesh_topology.h"
#include "geometry/uv_atlas.h"

namespace u3d {
namespace {

float uv_area(const Mesh& m, size_t f) {
  const Vec2f a = m.uvs[m.faces[f][0]], b = m.uvs[m.faces[f][1]], c = m.uvs[m.faces[f][2]];
  return 0.5f * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

// Number of texel centres (at `size` texels a side) strictly inside more than one UV triangle.
size_t doubly_covered_texels(const Mesh& m, int size) {
  std::vector<int> hits(size_t(size) * size, 0);
  for (size_t f = 0; f < m.faces.size(); ++f) {
    Vec2f q[3];
    for (int k = 0; k < 3; ++k) q[k] = m.uvs[m.faces[f][k]] * float(size);
    const float sign = uv_area(m, f) > 0 ? 1.f : -1.f;
    const int x0 = std::max(0, int(std::floor(std::min({q[0].x(), q[1].x(), q[2].x()}))));
    const int x1 = std::min(size - 1, int(std::ceil(std::max({q[0].x(), q[1].x(), q[2].x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({q[0].y(), q[1].y(), q[2].y()}))));
    const int y1 = std::min(size - 1, int(std::ceil(std::max({q[0].y(), q[1].y(), q[2].y()}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Vec2f p(x + 0.5f, y + 0.5f);
        bool inside = true;
        for (int k = 0; k < 3; ++k) {
          const Vec2f a = q[k], b = q[(k + 1) % 3];
          inside = inside && sign * ((b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x())) > 0.f;
        }
        hits[size_t(y) * size + x] += inside;
      }
  }
  size_t twice = 0;
  for (int h : hits) twice += h > 1;
  return twice;
}

size_t texels_closer_than_gutter(const UvAtlas& atlas, int size, int gutter);

void expect_valid_atlas(const Mesh& input, const UvAtlas& atlas, const UvAtlasOptions& options) {
  const Mesh& m = atlas.mesh;
  ASSERT_EQ(m.faces.size(), input.faces.size());
  ASSERT_EQ(m.uvs.size(), m.positions.size());
  ASSERT_EQ(atlas.source_vertex.size(), m.positions.size());
  for (size_t v = 0; v < m.positions.size(); ++v) {
    EXPECT_EQ(m.positions[v], input.positions[atlas.source_vertex[v]]);
    EXPECT_GE(m.uvs[v].minCoeff(), 0.f);
    EXPECT_LE(m.uvs[v].maxCoeff(), 1.f);
  }
  for (size_t f = 0; f < m.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(atlas.source_vertex[m.faces[f][k]], input.faces[f][k]);
    EXPECT_GT(uv_area(m, f), 0.f) << "face " << f << " is flipped or degenerate in UV";
  }
  EXPECT_EQ(doubly_covered_texels(m, options.texture_size), 0u);
  EXPECT_EQ(texels_closer_than_gutter(atlas, options.texture_size, options.gutter_texels), 0u);
}

// True when the closed triangle `q` and the open texel square [x, x + 1] x [y, y + 1] share a point
// of positive area (separating axes: the square's two, the triangle's three edge normals).
bool triangle_meets_texel(const std::array<Vec2f, 3>& q, int x, int y) {
  const std::array<Vec2f, 4> square = {Vec2f(x, y), Vec2f(x + 1, y), Vec2f(x + 1, y + 1), Vec2f(x, y + 1)};
  std::vector<Vec2f> axes = {Vec2f(1, 0), Vec2f(0, 1)};
  for (int k = 0; k < 3; ++k) axes.emplace_back(-(q[(k + 1) % 3] - q[k]).y(), (q[(k + 1) % 3] - q[k]).x());
  for (const Vec2f& axis : axes) {
    float t_lo = INFINITY, t_hi = -INFINITY, s_lo = INFINITY, s_hi = -INFINITY;
    for (const Vec2f& p : q) t_lo = std::min(t_lo, p.dot(axis)), t_hi = std::max(t_hi, p.dot(axis));
    for (const Vec2f& p : square) s_lo = std::min(s_lo, p.dot(axis)), s_hi = std::max(s_hi, p.dot(axis));
    if (t_hi <= s_lo || s_hi <= t_lo) return false;
  }
  return true;
}

// Texels that a chart's UV triangles touch (any overlap, not just the centre) and that lie within
// `gutter` texels (in x and y) of a texel another chart touches, or that two charts touch.
size_t texels_closer_than_gutter(const UvAtlas& atlas, int size, int gutter) {
  const Mesh& m = atlas.mesh;
  std::vector<int> owner(size_t(size) * size, -1);
  size_t shared = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    std::array<Vec2f, 3> q;
    for (int k = 0; k < 3; ++k) q[k] = m.uvs[m.faces[f][k]] * float(size);
    const int x0 = std::max(0, int(std::floor(std::min({q[0].x(), q[1].x(), q[2].x()}))));
    const int x1 = std::min(size - 1, int(std::floor(std::max({q[0].x(), q[1].x(), q[2].x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({q[0].y(), q[1].y(), q[2].y()}))));
    const int y1 = std::min(size - 1, int(std::floor(std::max({q[0].y(), q[1].y(), q[2].y()}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        if (!triangle_meets_texel(q, x, y)) continue;
        int& o = owner[size_t(y) * size + x];
        if (o >= 0 && o != atlas.face_chart[f]) ++shared;
        o = atlas.face_chart[f];
      }
  }
  size_t close = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int o = owner[size_t(y) * size + x];
      if (o < 0) continue;
      bool near_other = false;
      for (int dy = -gutter; dy <= gutter && !near_other; ++dy)
        for (int dx = -gutter; dx <= gutter && !near_other; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= size || ny >= size) continue;
          const int other = owner[size_t(ny) * size + nx];
          near_other = other >= 0 && other != o;
        }
      close += near_other;
    }
  return shared + close;
}

// Per chart, texels (UV area times size^2) per unit of surface area, over all its faces.
std::vector<double> chart_densities(const Mesh& input, const UvAtlas& atlas, int size) {
  std::vector<double> uv(atlas.chart_count, 0.0), surface(atlas.chart_count, 0.0);
  for (size_t f = 0; f < input.faces.size(); ++f) {
    const Vec3f& a = input.positions[input.faces[f][0]];
    uv[atlas.face_chart[f]] += double(uv_area(atlas.mesh, f)) * size * size;
    surface[atlas.face_chart[f]] +=
        0.5 * double((input.positions[input.faces[f][1]] - a).cross(input.positions[input.faces[f][2]] - a).norm());
  }
  std::vector<double> out(atlas.chart_count);
  for (int c = 0; c < atlas.chart_count; ++c) out[c] = uv[c] / surface[c];
  return out;
}

// A closed T (a bar on a post, 0.2 thick), extracted from a grid as reconstructions are: many small
// faces and normals that waver, so its charts have ragged borders.
Mesh t_shaped_body() {
  ScalarGrid grid;
  grid.nx = grid.ny = grid.nz = 97;
  grid.spacing = 2.f / 96.f;
  grid.origin = Vec3f(-1, -1, -1);
  grid.values.resize(size_t(97) * 97 * 97);
  auto box = [](const Vec3f& p, const Vec3f& lo, const Vec3f& hi) {  // > 0 inside, the distance to the nearest side
    return std::min({p.x() - lo.x(), hi.x() - p.x(), p.y() - lo.y(), hi.y() - p.y(), p.z() - lo.z(), hi.z() - p.z()});
  };
  for (int z = 0; z < 97; ++z)
    for (int y = 0; y < 97; ++y)
      for (int x = 0; x < 97; ++x) {
        const Vec3f p = grid.position(x, y, z);
        grid.values[grid.index(x, y, z)] = std::max(box(p, Vec3f(-0.9f, 0.5f, -0.1f), Vec3f(0.9f, 0.7f, 0.1f)),
                                                    box(p, Vec3f(-0.1f, -0.9f, -0.1f), Vec3f(0.1f, 0.7f, 0.1f)));
      }
  return extract_zero_surface(grid);
}

TEST(UvAtlas, SphereChartsArePackedWithoutOverlapOrFlips) {
  const Mesh sphere = make_icosphere(4, 0.7f);
  UvAtlasOptions options;
  options.texture_size = 512;
  const UvAtlas atlas = axis_chart_atlas(sphere, options);
  expect_valid_atlas(sphere, atlas, options);
  EXPECT_GE(atlas.chart_count, 6);
  EXPECT_LE(atlas.chart_count, 40);  // label smoothing keeps islands few
  EXPECT_GT(atlas.texel_efficiency, 0.55f);  // at 512 the 4-texel gutters take more of the atlas than at 2048
  EXPECT_LT(atlas.texel_efficiency, 1.f);
  // The seams are copies, not holes: welded, the surface is still closed.
  EXPECT_FALSE(mesh_topology(atlas.mesh).watertight);
  EXPECT_TRUE(surface_topology(atlas.mesh).closed_manifold());
  // Every chart has the packing's texels per unit of surface (squared: per unit area).
  for (double density : chart_densities(sphere, atlas, options.texture_size))
    EXPECT_NEAR(density, double(atlas.texels_per_unit) * atlas.texels_per_unit, 5e-3 * density);
  // texel_efficiency is the UV area of the faces over the atlas's.
  double uv = 0;
  for (size_t f = 0; f < sphere.faces.size(); ++f) uv += uv_area(atlas.mesh, f);
  EXPECT_NEAR(atlas.texel_efficiency, uv, 1e-4);
}

// At 2048 the charts are packed on cells of 2 x 2 texels; the gutter, 5 texels, rounds up to 3 cells.
TEST(UvAtlas, GuttersHoldOnTheCoarserPackingGrid) {
  const Mesh sphere = make_icosphere(3, 0.7f);
  UvAtlasOptions options;
  options.texture_size = 2048;
  options.gutter_texels = 5;
  const UvAtlas atlas = axis_chart_atlas(sphere, options);
  expect_valid_atlas(sphere, atlas, options);
  EXPECT_GT(atlas.texel_efficiency, 0.60f);
}

// The T's front and back charts fill little of their bounding boxes; cut across, they pack.
TEST(UvAtlas, SprawlingChartsAreCutSoTheAtlasFills) {
  const Mesh t = t_shaped_body();
  ASSERT_GT(t.face_count(), 10000u);
  UvAtlasOptions options;
  options.texture_size = 1024;
  const UvAtlas atlas = axis_chart_atlas(t, options);
  expect_valid_atlas(t, atlas, options);
  EXPECT_GT(atlas.texel_efficiency, 0.62f);
  UvAtlasOptions uncut = options;
  uncut.sprawl_share = 1.f;  // no chart has more than all of the surface: none is cut for filling little of its box
  const UvAtlas whole = axis_chart_atlas(t, uncut);
  EXPECT_LT(whole.chart_count, atlas.chart_count);
  EXPECT_LT(whole.texel_efficiency, atlas.texel_efficiency);
  for (double density : chart_densities(t, atlas, options.texture_size))
    EXPECT_NEAR(density, double(atlas.texels_per_unit) * atlas.texels_per_unit, 5e-3 * density);
}

// A helicoid of one and a half turns faces +Z everywhere but projects onto itself: its chart must be split.
TEST(UvAtlas, FoldedChartIsSplitUntilNoTexelIsSharedTwice) {
  Mesh helicoid;
  const int turns_steps = 120, radial = 6;
  for (int i = 0; i <= turns_steps; ++i)
    for (int j = 0; j <= radial; ++j) {
      const float t = 3.f * float(M_PI) * float(i) / turns_steps, r = 0.4f + 0.5f * float(j) / radial;
      helicoid.positions.emplace_back(r * std::cos(t), r * std::sin(t), 0.02f * t);
    }
  for (int i = 0; i < turns_steps; ++i)
    for (int j = 0; j < radial; ++j) {
      const int a = i * (radial + 1) + j, b = a + radial + 1;
      helicoid.faces.emplace_back(a, a + 1, b + 1);
      helicoid.faces.emplace_back(a, b + 1, b);
    }
  // Orient every face toward +Z (the helicoid's normals all lean that way).
  for (Vec3i& f : helicoid.faces)
    if (face_normals(helicoid.positions, {f})[0].z() < 0) std::swap(f[1], f[2]);
  UvAtlasOptions options;
  options.texture_size = 256;
  const UvAtlas atlas = axis_chart_atlas(helicoid, options);
  expect_valid_atlas(helicoid, atlas, options);
  EXPECT_GE(atlas.chart_count, 2);
}

TEST(UvAtlas, RejectsBadOptionsAndEmptyMeshes) {
  const Mesh sphere = make_icosphere(2, 0.5f);
  UvAtlasOptions small;
  small.texture_size = 8;
  EXPECT_THROW(axis_chart_atlas(sphere, small), Error);
  UvAtlasOptions negative;
  negative.gutter_texels = -1;
  EXPECT_THROW(axis_chart_atlas(sphere, negative), Error);
  UvAtlasOptions crowded;  // 320 faces' charts with 8-texel gutters cannot share 16 texels
  crowded.texture_size = 16;
  crowded.gutter_texels = 8;
  EXPECT_THROW(axis_chart_atlas(sphere, crowded), Error);
  EXPECT_THROW(axis_chart_atlas(Mesh{}, {}), Error);
}

}  // namespace
}  // namespace u3d
