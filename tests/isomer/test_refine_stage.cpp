// Stage 2: refinement recovers detail the coarse mesh lacks; ExplicitTarget resists a strongly
// inconsistent view better than the plain per-view loss; fusing only where views disagree reduces to
// the plain loss when no vertex's views disagree enough.
#include <gtest/gtest.h>

#include <cmath>

#include "core/progress.h"
#include "geometry/manifold_check.h"
#include "isomer/refine_stage.h"
#include "shape_fixtures.h"

using namespace u3d;
using namespace u3d::test;

namespace {

constexpr int kResolution = 192;

RefineStageOptions test_options() {
  RefineStageOptions o;
  o.end_edge_length = 0.02f;  // about 2 px per edge at this resolution; keeps the test mesh small
  return o;
}

}  // namespace

TEST(RefineStage, LowersNormalErrorOfACoarseMesh) {
  set_progress_quiet(true);
  const Mesh truth = bulged_ellipsoid();
  const std::vector<Camera> cameras = four_view_cameras(kResolution);
  const std::vector<Image> maps = render_normal_maps(truth, cameras);
  const Mesh coarse = plain_ellipsoid();
  StageReport report;
  const Mesh refined = run_refine_stage(coarse, {maps, cameras}, test_options(), &report);
  const double before = mean_normal_error_deg(coarse.positions, coarse.faces, maps, cameras);
  const double after = mean_normal_error_deg(refined.positions, refined.faces, maps, cameras);
  const double chamfer_before = chamfer_distance(surface_points(coarse.positions, coarse.faces),
                                                 surface_points(truth.positions, truth.faces));
  const double chamfer_after = chamfer_distance(surface_points(refined.positions, refined.faces),
                                                surface_points(truth.positions, truth.faces));
  printf("normal error %.2f -> %.2f deg, chamfer %.4f -> %.4f, %zu vertices, %.2f s\n", before, after,
         chamfer_before, chamfer_after, refined.positions.size(), report.seconds);
  EXPECT_EQ(closed_manifold_problem(refined.faces, refined.positions.size()), "");
  EXPECT_LT(after, 0.85 * before);
  EXPECT_LT(chamfer_after, chamfer_before);
}

// One view disagrees with the others (its normals are rotated about the vertical axis): the fused
// ExplicitTarget must end closer to the true shape than pulling toward every view separately.
TEST(RefineStage, ExplicitTargetBeatsPlainMultiViewLossOnInconsistentViews) {
  set_progress_quiet(true);
  const Mesh truth = bulged_ellipsoid();
  const std::vector<Camera> cameras = four_view_cameras(kResolution);
  const std::vector<Image> true_maps = render_normal_maps(truth, cameras);
  std::vector<Image> maps = true_maps;
  const float angle = 25.f * float(M_PI) / 180.f;
  Image& right = maps[int(View::Right)];
  for (size_t p = 0; p < right.pixel_count(); ++p) {
    float* px = right.data.data() + p * 4;
    const Vec3f n = Vec3f(px[0], px[1], px[2]) * 2.f - Vec3f::Ones();
    const Vec3f r(std::cos(angle) * n.x() + std::sin(angle) * n.z(), n.y(), -std::sin(angle) * n.x() + std::cos(angle) * n.z());
    for (int c = 0; c < 3; ++c) px[c] = std::clamp(0.5f * (r[c] + 1.f), 0.f, 1.f);
  }
  const Mesh coarse = plain_ellipsoid();
  RefineStageOptions et = test_options(), plain = test_options();
  et.target = RefineTarget::ExplicitTarget;
  plain.target = RefineTarget::MultiView;
  const Mesh with_et = run_refine_stage(coarse, {maps, cameras}, et);
  const Mesh without = run_refine_stage(coarse, {maps, cameras}, plain);
  const double error_et = mean_normal_error_deg(with_et.positions, with_et.faces, true_maps, cameras);
  const double error_plain = mean_normal_error_deg(without.positions, without.faces, true_maps, cameras);
  const double chamfer_et = chamfer_distance(surface_points(with_et.positions, with_et.faces),
                                             surface_points(truth.positions, truth.faces));
  const double chamfer_plain = chamfer_distance(surface_points(without.positions, without.faces),
                                                surface_points(truth.positions, truth.faces));
  printf("true-normal error: ET %.2f deg, plain %.2f deg; chamfer ET %.4f, plain %.4f\n", error_et, error_plain,
         chamfer_et, chamfer_plain);
  EXPECT_LT(error_et, error_plain);
}

// With a threshold above every possible disagreement no vertex is fused: the targets are the views' own
// maps, so the run is the multi-view loss's, vertex for vertex.
TEST(RefineStage, WhereViewsDisagreeAboveEveryDisagreementIsTheMultiViewLoss) {
  set_progress_quiet(true);
  const std::vector<Camera> cameras = four_view_cameras(kResolution);
  const std::vector<Image> maps = render_normal_maps(bulged_ellipsoid(), cameras);
  const Mesh coarse = plain_ellipsoid();
  RefineStageOptions plain = test_options(), partly = test_options(), everywhere = test_options();
  plain.steps = partly.steps = everywhere.steps = 10;
  plain.target = RefineTarget::MultiView;
  partly.target = everywhere.target = RefineTarget::WhereViewsDisagree;
  partly.disagreement_threshold = 2.f;  // normals are unit vectors: no spread reaches 2
  everywhere.disagreement_threshold = 0.f;
  const Mesh a = run_refine_stage(coarse, {maps, cameras}, plain);
  const Mesh b = run_refine_stage(coarse, {maps, cameras}, partly);
  const Mesh c = run_refine_stage(coarse, {maps, cameras}, everywhere);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_NE(a.positions, c.positions);  // and a threshold of 0 does fuse
}
