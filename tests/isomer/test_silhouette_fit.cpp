// Fitting a mesh to the visual hull of its masks (issue 14): a frame keeps its open bay when the
// initial mesh bridged it, crossed plate sheets become one plate of positive thickness, a separate
// part the mesh lost comes back, and what the mesh adds outside the masks is cut away.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/synthetic_views.h"
#include "geometry/test_shapes.h"
#include "geometry/mesh_topology.h"
#include "isomer/reconstruct.h"
#include "isomer/silhouette_check.h"
#include "isomer/silhouette_fit.h"

namespace u3d {
namespace {

using testing::Box;
using testing::boxes_views;
using test::box_mesh;

float min_iou(const Mesh& mesh, const ViewSet& views) {
  const std::array<float, 4> iou = silhouette_iou(mesh, views);
  return *std::min_element(iou.begin(), iou.end());
}

// A square frame in the xy plane (0.1 thick in z) with a 0.6 x 0.6 open bay in the middle.
std::vector<Box> frame() {
  return {{{-0.6f, -0.6f, -0.05f}, {0.6f, -0.3f, 0.05f}},
          {{-0.6f, 0.3f, -0.05f}, {0.6f, 0.6f, 0.05f}},
          {{-0.6f, -0.3f, -0.05f}, {-0.3f, 0.3f, 0.05f}},
          {{0.3f, -0.3f, -0.05f}, {0.6f, 0.3f, 0.05f}}};
}

TEST(SilhouetteFit, FrameKeepsItsHole) {
  const ViewSet views = boxes_views(frame(), 256);
  // The initial mesh bridged the bay: a solid slab over the whole frame, a little too thick as well.
  const Mesh bridged = box_mesh({-0.6f, -0.6f, -0.08f}, {0.6f, 0.6f, 0.08f});
  EXPECT_LT(min_iou(bridged, views), 0.7f);
  const Mesh fitted = fit_to_silhouettes(bridged, views, 192, 2000);
  EXPECT_LE(fitted.face_count(), 2000u);
  const MeshTopology topo = mesh_topology(fitted);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler_characteristic, 0);  // genus 1: the bay is a hole through the frame
  EXPECT_GT(min_iou(fitted, views), 0.97f);
  const double frame_volume = (1.2 * 1.2 - 0.6 * 0.6) * 0.1;
  EXPECT_NEAR(topo.volume / frame_volume, 1.0, 0.05);
}

// The front and back sheets of a 0.08 thick plate crossed (the mesh is the plate turned inside out):
// the fit gives the plate, right side out, with its thickness.
TEST(SilhouetteFit, CrossedPlateSheetsBecomeOnePlate) {
  const Vec3f lo(-0.5f, -0.6f, -0.04f), hi(0.5f, 0.6f, 0.04f);
  const ViewSet views = boxes_views({{lo, hi}}, 256);
  Mesh crossed = box_mesh(lo - Vec3f(0, 0, 0.02f), hi + Vec3f(0, 0, 0.02f));
  for (Vec3i& f : crossed.faces) std::swap(f[1], f[2]);
  const Mesh fitted = fit_to_silhouettes(crossed, views, 192, 2000);
  const MeshTopology topo = mesh_topology(fitted);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_NEAR(topo.volume / double((hi - lo).prod()), 1.0, 0.05);  // positive: outward, solid
  const BoundingBox box = bounding_box(fitted.positions);
  EXPECT_NEAR(box.min.z(), lo.z(), 0.011f);
  EXPECT_NEAR(box.max.z(), hi.z(), 0.011f);
  EXPECT_GT(min_iou(fitted, views), 0.97f);
}

// The optimisation thinned a plate to 40 % of its thickness: where the mesh fills most of the hull's
// column, the column is the hull's, and the plate gets its thickness back. A concavity the hull cannot
// see (a column the mesh fills less than 30 % of) keeps the mesh.
TEST(SilhouetteFit, ThinnedPlateGetsTheHullsThickness) {
  const Vec3f lo(-0.5f, -0.6f, -0.05f), hi(0.5f, 0.6f, 0.05f);
  const ViewSet views = boxes_views({{lo, hi}}, 256);
  const Mesh thinned = box_mesh({lo.x(), lo.y(), -0.02f}, {hi.x(), hi.y(), 0.02f});
  const Mesh fitted = fit_to_silhouettes(thinned, views, 192, 2000);
  const double ratio = mesh_topology(fitted).volume / double((hi - lo).prod());  // the mesh had 0.4
  EXPECT_GT(ratio, 0.9);  // within a voxel (0.0104) of the 0.1 thickness
  EXPECT_LT(ratio, 1.05);

  // A block with a pocket 0.8 deep open to the front: its back and its four walls are 0.2 thick, so
  // every column through the pocket (along z and along x) holds 20 % mesh: the pocket stays open.
  const ViewSet block_views = boxes_views({{{-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}}}, 256);
  Mesh pocketed;
  const std::vector<Box> parts = {{{-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, -0.3f}},  // back
                                  {{-0.5f, -0.5f, -0.5f}, {-0.4f, 0.5f, 0.5f}},  // left and right walls
                                  {{0.4f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}},
                                  {{-0.5f, -0.5f, -0.5f}, {0.5f, -0.4f, 0.5f}},  // bottom and top
                                  {{-0.5f, 0.4f, -0.5f}, {0.5f, 0.5f, 0.5f}}};
  for (const Box& b : parts) {
    const Mesh part = box_mesh(b.first, b.second);
    for (const Vec3i& f : part.faces) pocketed.faces.push_back(f + Vec3i::Constant(int(pocketed.positions.size())));
    pocketed.positions.insert(pocketed.positions.end(), part.positions.begin(), part.positions.end());
  }
  const Mesh kept = fit_to_silhouettes(pocketed, block_views, 192, 4000);
  EXPECT_NEAR(mesh_topology(kept).volume, 1.0 - 0.8 * 0.8 * 0.8, 0.03);
}

// A sign on a pole with a small box beside it; the mesh lost the box and bulges out of the masks
// above the sign. The fit brings the box back as its own part and cuts the bulge.
TEST(SilhouetteFit, LostPartComesBackAndExcessIsCut) {
  const std::vector<Box> parts = {{{-0.05f, -0.8f, -0.05f}, {0.05f, 0.3f, 0.05f}},  // pole
                                  {{-0.5f, 0.3f, -0.02f}, {0.5f, 0.7f, 0.02f}},     // sign
                                  {{0.3f, -0.8f, -0.15f}, {0.6f, -0.5f, 0.15f}}};   // box beside
  const ViewSet views = boxes_views(parts, 256);
  Mesh mesh = box_mesh(parts[0].first, parts[0].second);
  const Mesh sign = box_mesh({-0.5f, 0.3f, -0.02f}, {0.5f, 0.85f, 0.02f});  // 0.15 too tall
  for (const Vec3i& f : sign.faces) mesh.faces.push_back(f + Vec3i::Constant(int(mesh.positions.size())));
  mesh.positions.insert(mesh.positions.end(), sign.positions.begin(), sign.positions.end());
  const Mesh fitted = fit_to_silhouettes(mesh, views, 192, 3000);
  const MeshTopology topo = mesh_topology(fitted);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 2);  // pole and sign overlap into one part; the box is the other
  EXPECT_LT(bounding_box(fitted.positions).max.y(), 0.7f + 0.011f);
  EXPECT_GT(min_iou(fitted, views), 0.97f);
}

// Stage 1 keeps an initial mesh that agrees with the masks as it is, and fits one that misses most of
// a mask (a table: a thin top on four legs, where the integrated front and back sheets cross).
TEST(SilhouetteFit, InitialMeshIsFittedOnlyWhenItMissesAMask) {
  ReconstructOptions options;
  bool fitted = true;
  const ViewSet sphere = testing::sphere_views(0.6f, 128);
  const Mesh kept = stage_initial_mesh(sphere, options, &fitted);
  EXPECT_FALSE(fitted);
  EXPECT_EQ(kept.positions, build_initial_mesh(sphere, options.init).positions);

  std::vector<Box> table = {{{-0.8f, 0.3f, -0.5f}, {0.8f, 0.34f, 0.5f}}};
  for (float x : {-0.75f, 0.7f})
    for (float z : {-0.45f, 0.4f}) table.push_back({{x, -0.6f, z}, {x + 0.05f, 0.3f, z + 0.05f}});
  const ViewSet views = boxes_views(table, 256);
  const Mesh poisson = build_initial_mesh(views, options.init);
  ASSERT_LT(min_silhouette_iou(poisson, views), options.silhouette_fit.initial_min_iou);
  const Mesh fitted_frame = stage_initial_mesh(views, options, &fitted);
  EXPECT_TRUE(fitted);
  EXPECT_GT(min_silhouette_iou(fitted_frame, views), 0.9f);

  options.silhouette_fit.enabled = false;  // the ablation
  EXPECT_EQ(stage_initial_mesh(views, options, &fitted).positions, poisson.positions);
  EXPECT_FALSE(fitted);
}

TEST(SilhouetteFit, BadOptionsAreErrors) {
  const ViewSet views = boxes_views(frame(), 64);
  const Mesh mesh = box_mesh({-0.6f, -0.6f, -0.08f}, {0.6f, 0.6f, 0.08f});
  EXPECT_THROW(fit_to_silhouettes(mesh, views, 2, 2000), Error);
  EXPECT_THROW(fit_to_silhouettes(mesh, views, 64, 10), Error);
}

}  // namespace
}  // namespace u3d
