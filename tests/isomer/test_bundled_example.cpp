// The bundled example (examples/spot/views, rendered by `unique3d render` from examples/spot/spot.obj)
// reconstructs to a closed, manifold, fully coloured mesh that covers the input silhouettes.
//
// The IoU floors below are what the stages implemented so far (initial mesh, clean-up, colouring)
// reach; the side views are the weak ones because front/back integration cannot see depth steps
// (the head in front of the body). The optimisation stages that go between the initial mesh and the
// clean-up are what brings every view to >= 0.9.
#include <gtest/gtest.h>

#include "core/progress.h"
#include "isomer/mesh_topology.h"
#include "isomer/reconstruct.h"
#include "isomer/silhouette_check.h"

namespace u3d {
namespace {

TEST(BundledExample, SpotReconstructsClosedColouredAndOnTheSilhouettes) {
  set_progress_quiet(true);
  const ViewSet views = load_view_set(std::filesystem::path(UNIQUE3D_SOURCE_DIR) / "examples/spot/views");
  const ReconstructResult result = reconstruct(views);
  const Mesh& mesh = result.mesh;
  const MeshTopology topo = mesh_topology(mesh);
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_GT(topo.volume, 0.0);
  ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
  for (const Vec3f& c : mesh.colors) ASSERT_TRUE(c.allFinite() && c.minCoeff() >= 0.f && c.maxCoeff() <= 1.f);
  EXPECT_EQ(result.colouring.unreachable, 0u);
  const std::array<float, 4> iou = silhouette_iou(mesh, views);
  std::printf("spot: %zu faces, %s\nspot silhouette IoU: front %.4f right %.4f back %.4f left %.4f\n",
              mesh.face_count(), topo.summary().c_str(), iou[0], iou[1], iou[2], iou[3]);
  for (const StageTiming& t : result.timings) std::printf("spot stage %s: %.2f s\n", t.name.c_str(), t.seconds);
  EXPECT_GE(iou[0], 0.85f);
  EXPECT_GE(iou[2], 0.85f);
  EXPECT_GE(iou[1], 0.65f);
  EXPECT_GE(iou[3], 0.65f);
}

}  // namespace
}  // namespace u3d
