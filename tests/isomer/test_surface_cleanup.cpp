// The clean-up before colouring keeps a closed manifold closed and manifold, including when the
// optimisation left crumbs beside the surface (a 2-face "pillow" breaks Open3D's Loop subdivision).
#include <gtest/gtest.h>

#include "geometry/icosphere.h"
#include "geometry/mesh_topology.h"
#include "isomer/surface_cleanup.h"

namespace u3d {
namespace {

TEST(SurfaceCleanup, DropsCrumbsAndStaysClosedManifold) {
  Mesh mesh = make_icosphere(2, 0.8f);
  const Mesh horn = make_icosphere(1, 0.1f);  // a small real piece (80 faces) must survive
  const int base = int(mesh.positions.size());
  for (const Vec3f& p : horn.positions) mesh.positions.push_back(p + Vec3f(0.f, 1.f, 0.f));
  for (const Vec3i& f : horn.faces) mesh.faces.push_back(f + Vec3i::Constant(base));
  const int pillow = int(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), {{0.f, 0.f, 0.f}, {0.01f, 0.f, 0.f}, {0.f, 0.01f, 0.f}});
  mesh.faces.push_back({pillow, pillow + 1, pillow + 2});
  mesh.faces.push_back({pillow, pillow + 2, pillow + 1});
  ASSERT_EQ(mesh_topology(mesh).components, 3);

  SurfaceCleanupOptions options;
  options.subdivision_threshold = 0.f;  // subdivide both times
  const Mesh cleaned = smooth_and_subdivide(mesh, options);
  const MeshTopology topo = mesh_topology(cleaned);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_EQ(topo.components, 2) << topo.summary();
  EXPECT_EQ(cleaned.face_count(), (320u + 80u) * 16u);

  options.max_faces = (320u + 80u) * 4u;  // room for one step only
  EXPECT_EQ(smooth_and_subdivide(mesh, options).face_count(), (320u + 80u) * 4u);
}

}  // namespace
}  // namespace u3d
