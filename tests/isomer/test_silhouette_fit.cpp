// Fitting a mesh to the visual hull of its masks (issue 14): a frame keeps its open bay when the
// initial mesh bridged it, crossed plate sheets become one plate of positive thickness, a separate
// part the mesh lost comes back, and what the mesh adds outside the masks is cut away. The local fit
// (issue 40) brings a lost part back and keeps the rest of the surface.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/synthetic_views.h"
#include "geometry/test_shapes.h"
#include "geometry/icosphere.h"
#include "geometry/mesh_topology.h"
#include "geometry/quadric_decimation.h"
#include "isomer/reconstruct.h"
#include "isomer/silhouette_check.h"
#include "isomer/silhouette_fit.h"
#include "shape_fixtures.h"

namespace u3d {
namespace {

using testing::Box;
using testing::boxes_views;
using test::box_mesh;

float min_iou(const Mesh& mesh, const ViewSet& views) {
  const std::array<float, 4> iou = silhouette_iou(mesh, views);
  return *std::min_element(iou.begin(), iou.end());
}

// A square frame in the xy plane (0.09375 thick in z) with a 0.625 x 0.625 open bay in the middle; its
// faces lie on pixel borders of 256 px views (multiples of 1/128), so the masks show it exactly.
std::vector<Box> frame() {
  const float a = 0.5625f, b = 0.3125f, t = 0.046875f;
  return {{{-a, -a, -t}, {a, -b, t}}, {{-a, b, -t}, {a, a, t}}, {{-a, -b, -t}, {-b, b, t}}, {{b, -b, -t}, {a, b, t}}};
}

Mesh union_of(const std::vector<Box>& boxes) {
  Mesh mesh;
  for (const Box& b : boxes) {
    const Mesh part = box_mesh(b.first, b.second);
    for (const Vec3i& f : part.faces) mesh.faces.push_back(f + Vec3i::Constant(int(mesh.positions.size())));
    mesh.positions.insert(mesh.positions.end(), part.positions.begin(), part.positions.end());
  }
  return mesh;
}

TEST(SilhouetteFit, FrameKeepsItsHole) {
  const ViewSet views = boxes_views(frame(), 256);
  // The initial mesh bridged the bay: a solid slab over the whole frame, a little too thick as well.
  const Mesh bridged = box_mesh({-0.5625f, -0.5625f, -0.08f}, {0.5625f, 0.5625f, 0.08f});
  EXPECT_LT(min_iou(bridged, views), 0.7f);
  const Mesh fitted = fit_to_silhouettes(bridged, views, 192, 2000);
  EXPECT_LE(fitted.face_count(), 2000u);
  const MeshTopology topo = mesh_topology(fitted);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler_characteristic, 0);  // genus 1: the bay is a hole through the frame
  EXPECT_GT(min_iou(fitted, views), 0.97f);
  const double frame_volume = (1.125 * 1.125 - 0.625 * 0.625) * 0.09375;
  EXPECT_NEAR(topo.volume / frame_volume, 1.0, 0.02);
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
  const Mesh pocketed = union_of({{{-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, -0.3f}},  // back
                                  {{-0.5f, -0.5f, -0.5f}, {-0.4f, 0.5f, 0.5f}},  // left and right walls
                                  {{0.4f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}},
                                  {{-0.5f, -0.5f, -0.5f}, {0.5f, -0.4f, 0.5f}},  // bottom and top
                                  {{-0.5f, 0.4f, -0.5f}, {0.5f, 0.5f, 0.5f}}});
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
  const Mesh mesh = union_of({parts[0], {{-0.5f, 0.3f, -0.02f}, {0.5f, 0.85f, 0.02f}}});  // the sign 0.15 too tall
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

// A plate seen edge-on by every view (a table top; faces on pixel borders of 256 px views), and the
// same plate perforated: a 0.99 x 0.8 hole through its middle, open only to the top and the bottom.
const Vec3f kPlateLo(-0.59375f, -0.046875f, -0.5f), kPlateHi(0.59375f, 0.046875f, 0.5f);

Mesh perforated_plate() {
  const float a = kPlateHi.x(), t = kPlateHi.y();
  return union_of({{{-a, -t, 0.4f}, {a, t, 0.5f}},            // front rim
                   {{-a, -t, -0.5f}, {a, t, -0.4f}},          // back rim
                   {{-a, -t, -0.4f}, {-a + 0.1f, t, 0.4f}},   // left rim
                   {{a - 0.1f, -t, -0.4f}, {a, t, 0.4f}}});   // right rim
}

// A table top whose middle the mesh lost: a hole through the plate, open only to the top and the
// bottom, which no view looks from, so the silhouettes do not show it. Nothing the four views see
// explains the hole (each view sees the plate's rim in front of it), and the fit closes it; counting
// the mesh's share of the hull's columns alone keeps it (the rim fills 17-20 % of each column).
TEST(SilhouetteFit, HoleNoViewSeesIsClosed) {
  const Vec3f lo = kPlateLo, hi = kPlateHi;
  const float a = hi.x(), t = hi.y();
  const ViewSet views = boxes_views({{lo, hi}}, 256);
  const Mesh perforated = perforated_plate();
  EXPECT_GT(min_iou(perforated, views), 0.99f);
  const double plate = double((hi - lo).prod());
  const std::optional<float> fill = carved_hull_fill(perforated, views, 128);
  ASSERT_TRUE(fill.has_value());
  const double rims = 2.0 * (2.0 * a * 0.1 + 0.1 * 0.8) * 2.0 * t;
  EXPECT_NEAR(*fill, rims / plate, 0.03);  // what triggers the fit on an optimised mesh
  const std::optional<float> solid_fill = carved_hull_fill(box_mesh(lo, hi), views, 128);
  ASSERT_TRUE(solid_fill.has_value());
  EXPECT_NEAR(*solid_fill, 1.0, 0.03);

  const Mesh fitted = fit_to_silhouettes(perforated, views, 192, 2000);
  const MeshTopology topo = mesh_topology(fitted);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.euler_characteristic, 2);  // genus 0: the hole is closed
  EXPECT_NEAR(topo.volume / plate, 1.0, 0.03);
}

// The final check: a mesh that keeps its masks and its volume is left alone; the perforated table top
// above (a third of the plate's volume) gets the masks' hull, closed and solid.
TEST(SilhouetteFit, OptimisedMeshIsFittedOnlyWhenItLosesAMaskOrItsVolume) {
  const SilhouetteFitOptions options;
  const Vec3f lo = kPlateLo, hi = kPlateHi;
  const ViewSet views = boxes_views({{lo, hi}}, 256);
  const Mesh plate = box_mesh(lo, hi);
  EXPECT_FALSE(fit_optimised_mesh(plate, plate, views, options).has_value());

  const Mesh perforated = perforated_plate();
  const std::optional<Mesh> fitted = fit_optimised_mesh(perforated, perforated, views, options);
  ASSERT_TRUE(fitted.has_value());
  const MeshTopology topo = mesh_topology(*fitted);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.euler_characteristic, 2);
  EXPECT_NEAR(topo.volume / double((hi - lo).prod()), 1.0, 0.03);
}

// The mesh's face normals against the views' normal maps: a box explains its own maps (all but the
// pixels along its edges, where a face is seen edge-on), a sphere of the same size does not.
TEST(SilhouetteFit, NormalMapErrorMeasuresHowWellAMeshExplainsTheMaps) {
  const Vec3f lo(-0.5f, -0.4f, -0.3f), hi(0.5f, 0.4f, 0.3f);
  const ViewSet views = boxes_views({{lo, hi}}, 128);
  EXPECT_LT(normal_map_error(box_mesh(lo, hi), views), 1.f);
  EXPECT_GT(normal_map_error(make_icosphere(4, 0.5f), views), 20.f);
}

// Issue 40: an initial mesh with more pieces than the masks' hull (Poisson cut a part off and joined
// it across a gap) is joined and cut by the hull: the band across the gap goes, the part joins the
// body, and the rest of the mesh's surface is kept where the hull would be larger. Parts too far apart
// to join give way to the hull; a mesh whose pieces the hull has is kept.
TEST(SilhouetteFit, InitialMeshWithMorePiecesThanTheHullIsJoinedAndCut) {
  const Box body{{-0.5f, -0.5f, -0.25f}, {0.5f, 0.25f, 0.25f}};
  const Box left_horn{{-0.375f, 0.25f, -0.125f}, {-0.125f, 0.5f, 0.125f}};
  const Box right_horn{{0.125f, 0.25f, -0.125f}, {0.375f, 0.5f, 0.125f}};
  const ViewSet views = boxes_views({body, left_horn, right_horn}, 128);
  SilhouetteFitOptions options;  // 64^3: a sample is 1/32 apart, 2 px of these views
  // A body smaller than the masks allow (nothing contradicts it), and both horns in one piece with a
  // band across the gap between them, cut off the body by one sample.
  const Box smaller_body{{-0.375f, -0.375f, -0.1875f}, {0.375f, 0.25f, 0.1875f}};
  const Box horns_and_band{{-0.375f, 0.28125f, -0.125f}, {0.375f, 0.5f, 0.125f}};
  const std::optional<Mesh> joined =
      start_for_extra_pieces(union_of({smaller_body, horns_and_band}), views, options, 2000);
  ASSERT_TRUE(joined);
  MeshTopology topo = mesh_topology(*joined);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler_characteristic, 2);
  EXPECT_LE(joined->face_count(), 2000u);
  float widest = 0.f;
  for (const Vec3f& p : joined->positions) {
    EXPECT_FALSE(std::abs(p.x()) < 0.09f && p.y() > 0.3f) << "the band over the gap is kept at " << p.transpose();
    if (p.y() < 0.2f) widest = std::max(widest, std::abs(p.x()));
  }
  EXPECT_NEAR(widest, 0.375f, 0.02f);  // the smaller body's sides, not the hull's at 0.5
  const double horns = 2 * 0.25 * 0.25 * 0.25, kept = 0.75 * 0.625 * 0.375 + horns;
  EXPECT_NEAR(topo.volume, kept, 0.02);  // the hull holds 0.406
  // The horn floating too far above the body to join: the hull, with the masks' one piece.
  const Box horn{{-0.125f, 0.25f, -0.125f}, {0.125f, 0.5f, 0.125f}};
  const ViewSet one_horn = boxes_views({body, horn}, 128);
  const Box far{{-0.125f, 0.4375f, -0.125f}, {0.125f, 0.5f, 0.125f}};
  const std::optional<Mesh> hull = start_for_extra_pieces(union_of({body, far}), one_horn, options, 2000);
  ASSERT_TRUE(hull);
  topo = mesh_topology(*hull);
  EXPECT_TRUE(topo.closed_manifold());
  EXPECT_EQ(topo.components, 1);
  EXPECT_NEAR(topo.volume, 0.375 + 0.25 * 0.25 * 0.25, 0.02);
  EXPECT_GT(min_iou(*hull, one_horn), 0.95f);
  // One piece, or as many as the hull has: kept.
  EXPECT_FALSE(start_for_extra_pieces(union_of({body}), one_horn, options, 2000));
  const Box apart{{0.625f, -0.5f, -0.125f}, {0.875f, 0.f, 0.125f}};
  EXPECT_FALSE(start_for_extra_pieces(union_of({body, apart}), boxes_views({body, apart}, 128), options, 2000));
}

// Pieces hidden in every view behind or inside others go; a piece that shows pixels of its own stays.
TEST(SilhouetteFit, PiecesNoViewNeedsAreDropped) {
  const Box body{{-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}};
  const ViewSet views = boxes_views({body}, 64);
  const Box inside{{-0.25f, -0.25f, -0.25f}, {0.25f, 0.25f, 0.25f}};
  Mesh mesh = union_of({body, inside});
  drop_pieces_no_view_needs(mesh, views);
  EXPECT_EQ(mesh.face_count(), 12u);
  EXPECT_EQ(mesh.positions.size(), 8u);
  EXPECT_EQ(bounding_box(mesh.positions).max, body.second);
  // A crumb in front of a thin part, within a deep part's depth (signpost's crumbs in front of its
  // pole): the thin part covers its pixels in the front and back views, the deep one in the sides.
  const Box deep{{-0.5f, -0.5f, -0.5f}, {-0.125f, 0.5f, 0.5f}}, thin{{0.125f, -0.5f, -0.125f}, {0.5f, 0.5f, 0.125f}};
  const Box crumb{{0.25f, -0.0625f, 0.25f}, {0.375f, 0.0625f, 0.3125f}};
  mesh = union_of({deep, thin, crumb});
  drop_pieces_no_view_needs(mesh, boxes_views({deep, thin}, 64));
  EXPECT_EQ(mesh.face_count(), 24u);
  EXPECT_EQ(bounding_box(mesh.positions).max.x(), 0.5f);
  // Beside the body, it shows in the front view: kept.
  const Box beside{{0.625f, -0.0625f, -0.0625f}, {0.75f, 0.0625f, 0.0625f}};
  mesh = union_of({body, beside});
  drop_pieces_no_view_needs(mesh, views);
  EXPECT_EQ(mesh.face_count(), 24u);
}

// Positive inside an axis-aligned box: the distance to its nearest face inside, negative outside.
float box_field(const Vec3f& p, const Vec3f& lo, const Vec3f& hi) { return (p - lo).cwiseMin(hi - p).minCoeff(); }

// A block with a pit in its top that no view sees into (the block's walls hide it from the four
// horizontal views) and a round bump on its front, optionally with a thin post standing on the top's
// right rim (only the post shows above the block in every view): the grid surface of the shape's
// field, decimated. Volumes: block 0.49, pit 0.05, bump 0.0052, post 0.004.
Mesh block_with_pit_and_bump(bool with_post) {
  ScalarGrid grid;
  grid.nx = grid.ny = grid.nz = 91;
  grid.origin = Vec3f::Constant(-0.9f);
  grid.spacing = 0.02f;
  grid.values.resize(size_t(91 * 91 * 91));
  for (int z = 0; z < 91; ++z)
    for (int y = 0; y < 91; ++y)
      for (int x = 0; x < 91; ++x) {
        const Vec3f p = grid.position(x, y, z);
        const float block = std::min(box_field(p, {-0.5f, -0.5f, -0.35f}, {0.5f, 0.2f, 0.35f}),
                                     -box_field(p, {-0.25f, -0.05f, -0.2f}, {0.25f, 0.3f, 0.2f}));
        const float bump = 0.2f - (p - Vec3f(0.f, -0.15f, 0.25f)).norm();
        const float post = with_post ? box_field(p, {0.3f, 0.15f, -0.05f}, {0.4f, 0.6f, 0.05f}) : -1.f;
        grid.values[grid.index(x, y, z)] = std::max({block, bump, post});
      }
  return decimate_closed_mesh(extract_zero_surface(grid), 16000);
}

// Issue 40: an optimised mesh that keeps its volume but lost a thin part (the post) is fitted locally:
// the part comes back, and the rest of its surface is kept, the pit that no view sees included. The
// whole-object fit of the same mesh fills the pit (no view sees it empty); the masks' hull also
// fills it and draws the bump as a ridge across the whole front, which the normal maps rule out.
TEST(SilhouetteFit, LocalFitRestoresALostPartAndKeepsTheRest) {
  const Mesh truth = block_with_pit_and_bump(true), mesh = block_with_pit_and_bump(false);
  const std::vector<Image> maps = test::render_normal_maps(truth, test::four_view_cameras(256));
  std::array<Image, 4> rgb, normals;
  std::array<std::string, 4> rgb_names, normal_names;
  for (View v : kAllViews) {
    const size_t k = size_t(v);
    normals[k] = maps[k];
    rgb[k] = Image(256, 256, 4, 0.5f);
    for (size_t p = 0; p < rgb[k].pixel_count(); ++p) rgb[k].data[p * 4 + 3] = maps[k].data[p * 4 + 3];
    rgb_names[k] = view_file_name(v, false);
    normal_names[k] = view_file_name(v, true);
  }
  const ViewSet views = make_view_set(rgb, normals, NormalSpace::World, rgb_names, normal_names);
  const double truth_volume = mesh_topology(truth).volume;
  EXPECT_NEAR(truth_volume, 0.49 - 0.05 + 0.0052 + 0.004, 0.004);
  EXPECT_LT(min_iou(mesh, views), 0.96f);  // the post is missing
  const std::optional<float> fill = carved_hull_fill(mesh, views, 128);
  ASSERT_TRUE(fill.has_value());
  EXPECT_GT(*fill, 0.85f);  // the pit is the carved hull's only volume the mesh lacks, with the post

  SilhouetteFitOptions options;
  options.final_resolution = 128;
  options.final_faces = 20000;
  const std::optional<Mesh> fitted = fit_optimised_mesh(mesh, mesh, views, options);
  ASSERT_TRUE(fitted.has_value());
  const MeshTopology topo = mesh_topology(*fitted);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_GT(min_iou(*fitted, views), 0.97f);                           // the post is back
  EXPECT_NEAR(topo.volume, truth_volume, 0.012);                       // and the pit kept (0.05)
  EXPECT_NEAR(bounding_box(fitted->positions).max.z(), 0.45f, 0.02f);  // the bump's front

  const Mesh whole = fit_to_silhouettes(mesh, views, 128, 20000);
  EXPECT_GT(mesh_topology(whole).volume, truth_volume + 0.035);  // the pit filled
}

TEST(SilhouetteFit, BadOptionsAreErrors) {
  const ViewSet views = boxes_views(frame(), 64);
  const Mesh mesh = box_mesh({-0.6f, -0.6f, -0.08f}, {0.6f, 0.6f, 0.08f});
  EXPECT_THROW(fit_to_silhouettes(mesh, views, 2, 2000), Error);
  EXPECT_THROW(fit_to_silhouettes(mesh, views, 64, 10), Error);
  EXPECT_THROW(fit_locally(mesh, views, 2, 2000), Error);
}

}  // namespace
}  // namespace u3d
