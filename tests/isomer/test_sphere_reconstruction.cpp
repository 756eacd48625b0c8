// An analytic quality gate of the reconstruction: a sphere of known radius from its exact views comes
// back with the right radius everywhere, measured as the mean distance |‖p‖ - r| of area-uniform surface
// samples from the sphere. The bound is the value measured on 2026-12-05 with a stated margin; next to
// it, what a near-absent optimisation (1 coarse and 1 refinement step) gives, which the bound rejects.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/progress.h"
#include "core/synthetic_views.h"
#include "geometry/surface_sampling.h"
#include "isomer/reconstruct.h"

namespace u3d {
namespace {

TEST(SphereReconstruction, RadiusIsRecoveredEverywhere) {
  set_progress_quiet(true);
  constexpr float kRadius = 0.6f;
  ReconstructOptions options;
  options.coarse.steps = 60;  // shortened, as the CLI's sphere test
  options.refine.steps = 20;
  options.cleanup.subdivision_iterations = 0;
  options.color_mode = ColorMode::Vertex;
  const Mesh mesh = reconstruct(testing::sphere_views(kRadius, 128), options).mesh;
  const SurfaceSamples samples = sample_surface(mesh.positions, mesh.faces, 20000, /*seed=*/1);
  double sum = 0, worst = 0;
  for (const Vec3f& p : samples.points) {
    const double e = std::abs(double(p.norm()) - kRadius);
    sum += e;
    worst = std::max(worst, e);
  }
  const double mean = sum / double(samples.points.size());
  std::printf("sphere r = %.2f: mean radial error %.5f, largest %.5f (a pixel of the views: %.5f)\n", kRadius, mean,
              worst, 2.0 / 128);
  // Measured: 0.00420 (a quarter of a pixel). Bound 30 % above; with 1 coarse and 1 refinement step the
  // initial mesh, nearly unchanged, gives 0.00721.
  EXPECT_LT(mean, 0.0055);
}

}  // namespace
}  // namespace u3d
