// The visual hull of four exact views: closed-form shapes (a sphere's hull is two crossed cylinders,
// a box's hull is the box), closed and outward, and clear errors for masks that carve nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "core/error.h"
#include "geometry/manifold_check.h"
#include "geometry/mesh_topology.h"
#include "isomer/silhouette_check.h"
#include "isomer/visual_hull.h"
#include "core/synthetic_views.h"

namespace u3d {
namespace {

// Every edge used once in each direction, every vertex a single fan.
bool closed_and_oriented(const Mesh& m) { return closed_manifold_problem(m.faces, m.positions.size()).empty(); }

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// The hull of a sphere from the four axis views (front/back along z, right/left along x) is the
// intersection of two cylinders of radius r along z and x: volume 16/3 r^3, extent [-r, r]^3.
TEST(VisualHull, SphereCarvesToTheBicylinder) {
  const float r = 0.6f;
  const ViewSet views = testing::sphere_views(r, 256);
  const int resolution = 128;
  const float voxel = 2.f / resolution;
  const Mesh hull = carve_visual_hull(views, {resolution, 0});
  EXPECT_TRUE(closed_and_oriented(hull));
  const MeshTopology topo = mesh_topology(hull);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  const double exact = 16.0 / 3.0 * r * r * r;
  EXPECT_NEAR(topo.volume / exact, 1.0, 0.01) << topo.volume << " vs " << exact;
  const BoundingBox box = bounding_box(hull.positions);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(box.min[i], -r, voxel) << i;
    EXPECT_NEAR(box.max[i], r, voxel) << i;
  }
  // Points of the bicylinder's surface: on one cylinder and inside the other.
  for (const Vec3f& p : hull.positions) {
    const float along_z = std::hypot(p.x(), p.y()), along_x = std::hypot(p.z(), p.y());
    EXPECT_LT(std::max(along_z, along_x), r + 0.5f * voxel);
    EXPECT_GT(std::max(along_z, along_x), r - voxel);
  }

  // Decimated (the default path): still closed and outward, with the same volume.
  const Mesh small = carve_visual_hull(views, {resolution, 5000});
  EXPECT_LE(small.face_count(), 5000u);
  EXPECT_TRUE(closed_and_oriented(small));
  const MeshTopology small_topo = mesh_topology(small);
  EXPECT_TRUE(small_topo.closed_manifold()) << small_topo.summary();
  EXPECT_NEAR(small_topo.volume / exact, 1.0, 0.01);
}

// An off-centre box, different in every axis: a mixed-up view axis or sign would move or resize it.
TEST(VisualHull, BoxCarvesToTheBox) {
  // Faces on pixel borders of the 256 px views (multiples of 1/128).
  const Vec3f lo(0.125f, -0.25f, -0.75f), hi(0.625f, 0.375f, -0.125f);
  const int resolution = 128;
  const float voxel = 2.f / resolution;
  const Mesh hull = carve_visual_hull(testing::boxes_views({{lo, hi}}, 256), {resolution, 0});
  EXPECT_TRUE(closed_and_oriented(hull));
  const MeshTopology topo = mesh_topology(hull);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  const double exact = double((hi - lo).prod());
  EXPECT_NEAR(topo.volume / exact, 1.0, 0.01) << topo.volume << " vs " << exact;
  const BoundingBox box = bounding_box(hull.positions);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(box.min[i], lo[i], 1e-4f) << i;
    EXPECT_NEAR(box.max[i], hi[i], 1e-4f) << i;
  }
  // Every vertex on the box's surface, except the chamfer along its edges (within a voxel).
  for (const Vec3f& p : hull.positions) {
    const Vec3f to_faces = (p - lo).cwiseMin(hi - p);
    EXPECT_GT(to_faces.minCoeff(), -1e-4f);
    EXPECT_LT(to_faces.minCoeff(), voxel);
  }
}

// A plate 5.5 pixels thick whose faces lie off the pixel borders, carved on voxels four pixels wide (as
// a 256^3 grid against 1024 px views): the field is the masks' distance to their outline, linear
// across a voxel, so the surface still passes where the masks' edges are. (Alpha itself, flat a pixel
// away from an edge, put it halfway between two samples: IoU 0.75 on the plate's edge-on views.)
TEST(VisualHull, ThinPlateOffThePixelGridKeepsItsSilhouettes) {
  const Vec3f lo(-0.513f, -0.377f, -0.0217f), hi(0.547f, 0.611f, 0.0213f);
  const ViewSet views = testing::boxes_views({{lo, hi}}, 256);
  const Mesh hull = carve_visual_hull(views, {64, 0});
  const std::array<float, 4> iou = silhouette_iou(hull, views);  // boxes_views: RGB and normal masks agree
  for (View v : kAllViews) EXPECT_GT(iou[size_t(v)], 0.98f) << view_name(v);
}

TEST(VisualHull, FieldIsPositiveExactlyInsideEveryMask) {
  const Vec3f lo(0.125f, -0.25f, -0.75f), hi(0.625f, 0.375f, -0.125f);
  const int resolution = 32;
  const ScalarGrid field = visual_hull_field(testing::boxes_views({{lo, hi}}, 64), resolution);
  ASSERT_EQ(field.nx, resolution + 2);
  int inside = 0;
  for (int z = 0; z < field.nz; ++z)
    for (int y = 0; y < field.ny; ++y)
      for (int x = 0; x < field.nx; ++x) {
        const Vec3f p = field.position(x, y, z);
        const bool in_box = (p - lo).minCoeff() > 0.f && (hi - p).minCoeff() > 0.f;
        EXPECT_EQ(field.values[field.index(x, y, z)] > 0.f, in_box) << p.transpose();
        inside += in_box;
      }
  EXPECT_EQ(inside, 8 * 10 * 10);  // voxels of 1/16: 0.5 x 0.625 x 0.625
}

TEST(VisualHull, EmptyOrDisjointMasksAreErrors) {
  ViewSet views = testing::sphere_views(0.6f, 64);
  ViewSet empty = views;
  for (size_t p = 0; p < empty[View::Right].rgb.pixel_count(); ++p) empty[View::Right].rgb.data[p * 4 + 3] = 0.f;
  EXPECT_NE(error_of([&] { carve_visual_hull(empty, {32, 0}); }).find("right mask is empty"), std::string::npos);

  // Front and back keep only the top of the disc, the sides only the bottom: no point is in all four.
  ViewSet disjoint = views;
  for (View v : kAllViews) {
    Image& rgb = disjoint[v].rgb;
    const bool keep_top = v == View::Front || v == View::Back;
    for (int y = 0; y < rgb.height; ++y)
      if ((y < rgb.height / 2) != keep_top)
        for (int x = 0; x < rgb.width; ++x) rgb.at(x, y, 3) = 0.f;
  }
  EXPECT_NE(error_of([&] { carve_visual_hull(disjoint, {32, 0}); }).find("share no volume"), std::string::npos);
  EXPECT_NE(error_of([&] { carve_visual_hull(views, {2, 0}); }).find("resolution"), std::string::npos);
}

}  // namespace
}  // namespace u3d
