// Axis-aligned chart atlas: UVs inside the atlas, every face counter-clockwise, no texel claimed by
// two faces (also on a helicoid, whose charts fold over themselves), gutters between charts, and the
// geometry unchanged but for the seam copies.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "geometry/icosphere.h"
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
  // Charts' UV boxes, in texels, are at least a gutter apart.
  std::vector<Eigen::AlignedBox2f> boxes(atlas.chart_count);
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) boxes[atlas.face_chart[f]].extend(m.uvs[m.faces[f][k]] * float(options.texture_size));
  for (int a = 0; a < atlas.chart_count; ++a)
    for (int b = a + 1; b < atlas.chart_count; ++b) {
      const float gap = std::max({boxes[b].min().x() - boxes[a].max().x(), boxes[a].min().x() - boxes[b].max().x(),
                                  boxes[b].min().y() - boxes[a].max().y(), boxes[a].min().y() - boxes[b].max().y()});
      EXPECT_GE(gap, float(options.gutter_texels)) << "charts " << a << " and " << b;
    }
}

TEST(UvAtlas, SphereChartsArePackedWithoutOverlapOrFlips) {
  const Mesh sphere = make_icosphere(4, 0.7f);
  UvAtlasOptions options;
  options.texture_size = 512;
  const UvAtlas atlas = axis_chart_atlas(sphere, options);
  expect_valid_atlas(sphere, atlas, options);
  EXPECT_GE(atlas.chart_count, 6);
  EXPECT_LE(atlas.chart_count, 40);  // label smoothing keeps islands few
  EXPECT_GT(atlas.texel_efficiency, 0.35f);
  EXPECT_LT(atlas.texel_efficiency, 1.f);
  // The seams are copies, not holes: welded, the surface is still closed.
  EXPECT_FALSE(mesh_topology(atlas.mesh).watertight);
  EXPECT_TRUE(surface_topology(atlas.mesh).closed_manifold());
  // The packing scale is the one every chart shares: a face's UV area is its projected area times it.
  const float scale = atlas.texels_per_unit / float(options.texture_size);
  for (size_t f = 0; f < sphere.faces.size(); f += 97) {
    const Vec3f n = face_normals(sphere.positions, {sphere.faces[f]})[0];
    const Vec3f e1 = sphere.positions[sphere.faces[f][1]] - sphere.positions[sphere.faces[f][0]];
    const Vec3f e2 = sphere.positions[sphere.faces[f][2]] - sphere.positions[sphere.faces[f][0]];
    const float area = 0.5f * e1.cross(e2).norm();
    const float cos_axis = n.cwiseAbs().maxCoeff();  // at least; smoothing may pick a lesser axis
    EXPECT_LE(uv_area(atlas.mesh, f), area * scale * scale * 1.001f);
    EXPECT_GE(uv_area(atlas.mesh, f), area * scale * scale * std::min(cos_axis, options.min_axis_cos) * 0.999f);
  }
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
