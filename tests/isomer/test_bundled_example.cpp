// The bundled example (examples/spot/views, rendered by `unique3d render` from examples/spot/spot.obj)
// reconstructs to a closed, manifold, textured mesh whose four views overlap the input masks
// with IoU >= 0.9 (the initial mesh alone reaches only ~0.87 front/back and ~0.71 on the sides: the
// coarse stage is what moves the silhouettes onto the masks).
//
// It is also one piece with no geometry over the background: screened Poisson joined the horns by a
// band across the gap between them and cut them off the head, and the band survived as a wire over the
// background (issue 40; measured as `unique3d eval --views` does, eval/mask_agreement.h).
//
// The optimisation stages run shortened here (coarse 100 of 200 steps, refinement 20 of 100, one
// subdivision) to keep the test near half a minute; the CLI test runs the full default once.
#include <gtest/gtest.h>

#include <cmath>

#include "core/progress.h"
#include "eval/mask_agreement.h"
#include "geometry/mesh_topology.h"
#include "isomer/reconstruct.h"
#include "isomer/silhouette_check.h"

namespace u3d {
namespace {

TEST(BundledExample, SpotReconstructsClosedTexturedAndOnTheSilhouettes) {
  set_progress_quiet(true);
  const ViewSet views = load_view_set(std::filesystem::path(UNIQUE3D_SOURCE_DIR) / "examples/spot/views");
  ReconstructOptions options;
  options.coarse.steps = 100;
  options.refine.steps = 20;
  options.cleanup.subdivision_iterations = 1;
  const ReconstructResult result = reconstruct(views, options);
  const Mesh& mesh = result.mesh;
  const MeshTopology topo = surface_topology(mesh);  // the atlas splits vertices at chart borders
  EXPECT_TRUE(topo.closed_manifold()) << topo.summary();
  EXPECT_GT(topo.volume, 0.0);
  EXPECT_LE(mesh.face_count(), kDefaultTextureFaces);
  ASSERT_TRUE(mesh.has_texture());
  ASSERT_EQ(mesh.uvs.size(), mesh.positions.size());
  for (float v : mesh.materials[0].texture.data) ASSERT_TRUE(std::isfinite(v) && v >= 0.f && v <= 1.f);
  EXPECT_EQ(result.coloring.unreachable, 0u);
  const std::array<float, 4> iou = silhouette_iou(mesh, views);
  std::printf("spot: %zu faces, %s\nspot silhouette IoU: front %.4f right %.4f back %.4f left %.4f\n",
              mesh.face_count(), topo.summary().c_str(), iou[0], iou[1], iou[2], iou[3]);
  for (const StageTiming& t : result.timings) std::printf("spot stage %s: %.2f s\n", t.name.c_str(), t.seconds);
  for (float v : iou) EXPECT_GE(v, 0.9f);
  EXPECT_EQ(topo.components, 1);
  const MaskAgreement agreement = mask_agreement(mesh, views);
  for (View v : kAllViews) EXPECT_LE(agreement.views[size_t(v)].spurious.largest_blob, 10u) << view_name(v);
  const std::vector<std::string> stages = {"initial mesh", "coarse", "refine", "smooth and subdivide", "silhouette fit",
                                           "decimate", "texture"};
  ASSERT_EQ(result.timings.size(), stages.size());
  for (size_t i = 0; i < stages.size(); ++i) EXPECT_EQ(result.timings[i].name, stages[i]);
}

TEST(BundledExample, ReconstructionIsDeterministic) {
  set_progress_quiet(true);
  const ViewSet views = load_view_set(std::filesystem::path(UNIQUE3D_SOURCE_DIR) / "examples/spot/views");
  ReconstructOptions options;
  options.coarse.steps = 30;
  options.refine.steps = 5;
  options.cleanup.subdivision_iterations = 0;
  const Mesh a = reconstruct(views, options).mesh;
  const Mesh b = reconstruct(views, options).mesh;
  ASSERT_EQ(a.faces, b.faces);
  ASSERT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.uvs, b.uvs);
  EXPECT_EQ(a.materials[0].texture.data, b.materials[0].texture.data);
}

}  // namespace
}  // namespace u3d
