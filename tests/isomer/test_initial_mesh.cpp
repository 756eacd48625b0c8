// The initial mesh of a sphere's four views: closed, manifold, ~2,000 faces, close to the sphere.
#include <gtest/gtest.h>

#include <random>

#include "core/synthetic_views.h"
#include "core/view_set.h"
#include "geometry/manifold_check.h"
#include "geometry/mesh_topology.h"
#include "isomer/initial_mesh.h"

namespace u3d {
namespace {

// Symmetric Chamfer distance (mean of both one-sided mean distances) between the mesh vertices and
// points sampled uniformly on the sphere.
double chamfer_to_sphere(const Mesh& mesh, float radius) {
  double to_sphere = 0;
  for (const Vec3f& p : mesh.positions) to_sphere += std::abs(p.norm() - radius);
  to_sphere /= double(mesh.positions.size());
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss;
  double to_mesh = 0;
  const int samples = 3000;
  for (int s = 0; s < samples; ++s) {
    const Vec3f q = Vec3f(gauss(rng), gauss(rng), gauss(rng)).normalized() * radius;
    float best = 1e9f;
    for (const Vec3f& p : mesh.positions) best = std::min(best, (p - q).squaredNorm());
    to_mesh += std::sqrt(best);
  }
  return 0.5 * (to_sphere + to_mesh / samples);
}

TEST(InitialMesh, SphereDepthPlacementIsCentred) {
  const ViewSet views = testing::sphere_views(0.6f, 256);
  const DepthSheets sheets = integrate_front_and_back(views);
  EXPECT_NEAR(sheets.z_min, -0.6f, 2.f / 256);
  EXPECT_NEAR(sheets.z_max, 0.6f, 2.f / 256);
  EXPECT_NEAR(sheets.rim_z, 0.f, 0.02f);
  // The integrated hemisphere is almost exactly the right height already.
  EXPECT_NEAR(sheets.scale, 1.f, 0.1f);
}

TEST(InitialMesh, SphereIsClosedManifoldAndClose) {
  const float radius = 0.6f;
  const Mesh mesh = build_initial_mesh(testing::sphere_views(radius, 256));
  const MeshTopology topo = mesh_topology(mesh);
  std::printf("sphere init: %zu faces, %s\n", mesh.face_count(), topo.summary().c_str());
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler_characteristic, 2);
  EXPECT_GT(topo.volume, 0.0);
  EXPECT_NEAR(double(mesh.face_count()), 2000.0, 200.0);
  const double cd = chamfer_to_sphere(mesh, radius);
  std::printf("sphere init: Chamfer distance %.4f (radius %.2f)\n", cd, radius);
  EXPECT_LT(cd, 0.02);  // 3.3% of the radius
}

// The bundled example's initial mesh: Poisson + decimation + removal of non-manifold edges opened
// holes there; the optimisation's culling renderer needs every edge paired with its reverse.
TEST(InitialMesh, BundledExampleIsClosedAndConsistentlyOriented) {
  const ViewSet views = load_view_set(std::string(UNIQUE3D_SOURCE_DIR) + "/examples/spot/views");
  const Mesh mesh = build_initial_mesh(views);
  EXPECT_EQ(closed_manifold_problem(mesh.faces, mesh.positions.size()), "");
  EXPECT_GT(mesh_topology(mesh).volume, 0.0);
}

}  // namespace
}  // namespace u3d
