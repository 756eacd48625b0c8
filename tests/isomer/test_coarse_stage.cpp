// Stage 1 converges from a sphere to a known shape given its exact four normal maps.
#include <gtest/gtest.h>

#include "core/progress.h"
#include "geometry/manifold_check.h"
#include "isomer/coarse_stage.h"
#include "shape_fixtures.h"

using namespace u3d;
using namespace u3d::test;

TEST(CoarseStage, SphereConvergesToTheShapeOfItsFourViews) {
  set_progress_quiet(true);
  const Mesh truth = bulged_ellipsoid();
  const std::vector<Camera> cameras = four_view_cameras(256);
  const std::vector<Image> maps = render_normal_maps(truth, cameras);
  const Mesh start = sphere_initial_mesh();
  StageReport report;
  const Mesh result = run_coarse_stage(start, {maps, cameras}, CoarseStageOptions::from_sphere(), &report);
  const double before = chamfer_distance(surface_points(start.positions, start.faces),
                                         surface_points(truth.positions, truth.faces));
  const double after = chamfer_distance(surface_points(result.positions, result.faces),
                                        surface_points(truth.positions, truth.faces));
  printf("chamfer before %.4f after %.4f, %zu vertices, %.2f s, loss %.5f, edge %.4f\n", before, after,
         result.positions.size(), report.seconds, report.final_loss, report.final_edge_length);
  EXPECT_EQ(closed_manifold_problem(result.faces, result.positions.size()), "");
  EXPECT_LT(after, 0.015);
  EXPECT_LT(after, 0.2 * before);
}
