// The continuous-remeshing optimizer minimises a simple geometric energy while remeshing every step.
#include <gtest/gtest.h>

#include "geometry/icosphere.h"
#include "geometry/manifold_check.h"
#include "isomer/mesh_optimizer.h"

using namespace u3d;

// Pull a sphere of radius 0.5 onto radius 0.8: gradient of 0.5 (|p| - 0.8)^2 per vertex.
TEST(MeshOptimizer, InflatesASphereAndShrinksEdgesOnceSettled) {
  Mesh m = make_icosphere(2, 0.5f);
  MeshOptimizerOptions o;
  o.min_edge_length = 0.05f;
  o.max_edge_length = 0.2f;
  o.local_edge_length = false;
  MeshOptimizer opt(m.positions, m.faces, o);
  std::vector<Vec3f> grad;
  for (int step = 0; step < 150; ++step) {
    const std::vector<Vec3f>& p = opt.positions();
    grad.resize(p.size());
    for (size_t v = 0; v < p.size(); ++v) grad[v] = (p[v].norm() - 0.8f) * p[v].normalized();
    opt.step(grad);
    opt.remesh();
    if (step % 25 == 24) {
      ASSERT_EQ(closed_manifold_problem(opt.faces(), opt.positions().size()), "") << "step " << step;
    }
  }
  double radius = 0, worst = 0;
  for (const Vec3f& p : opt.positions()) radius += p.norm(), worst = std::max(worst, double(std::abs(p.norm() - 0.8f)));
  radius /= double(opt.positions().size());
  EXPECT_NEAR(radius, 0.8, 0.01);
  EXPECT_LT(worst, 0.05);
  // Settled vertices move slowly, so the controller drove the reference length to its minimum, and the
  // remesher followed: the state rows travelled with every collapse and split.
  EXPECT_NEAR(opt.mean_reference_edge_length(), o.min_edge_length, 1e-4);
  for (size_t v = 0; v < opt.rows().count(); ++v) {
    EXPECT_TRUE(opt.rows().position(v).isApprox(opt.positions()[v]));
    EXPECT_GE(opt.rows().row(v)[MeshOptimizer::kM2], 0.f);
  }
  EXPECT_GT(opt.positions().size(), 4 * m.vertex_count());
}
