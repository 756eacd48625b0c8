// The bundled example (examples/spot/views, rendered by `unique3d render` at fill 0.9 from
// examples/spot/spot.obj) reconstructs to a closed, manifold, textured mesh whose four views overlap the
// input masks with IoU >= 0.9 (the initial mesh alone reaches only ~0.87 front/back and ~0.71 on the
// sides: the coarse stage is what moves the silhouettes onto the masks).
//
// The silhouettes alone say little: the silhouette fit brings every view's IoU to about 0.999 whatever the
// optimisation did. So the result is also compared with the ground truth: Chamfer distance and F-score
// against spot.obj in the frame the views were rendered in (eval/evaluate.h, as `unique3d eval
// --given-frame --gt-render-fill 0.9`), with the fit and without it, and the textured mesh rendered back
// from the four views against the input colour images (PSNR). Each bound is the value measured on
// 2026-12-05 with a stated margin; next to it, what a near-absent optimisation (1 coarse and 1 refinement
// step) gives, which the bound rejects.
//
// It is also one piece with no geometry over the background: screened Poisson joined the horns by a
// band across the gap between them and cut them off the head, and the band survived as a wire over the
// background (issue 40; measured as `unique3d eval --views` does, eval/mask_agreement.h).
//
// The optimisation stages run shortened here (coarse 100 of 200 steps, refinement 20 of 100, one
// subdivision) to keep each test to seconds; the CLI test runs the full default once and checks it
// against the ground truth through `unique3d eval`.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/progress.h"
#include "eval/appearance.h"
#include "eval/evaluate.h"
#include "eval/image_metrics.h"
#include "eval/mask_agreement.h"
#include "geometry/mesh_topology.h"
#include "io/mesh_io.h"
#include "isomer/reconstruct.h"
#include "isomer/silhouette_check.h"
#include "render/render_view.h"

namespace u3d {
namespace {

const std::filesystem::path kSpot = std::filesystem::path(UNIQUE3D_SOURCE_DIR) / "examples/spot";

ReconstructOptions shortened_options() {
  ReconstructOptions options;
  options.coarse.steps = 100;
  options.refine.steps = 20;
  options.cleanup.subdivision_iterations = 1;
  return options;
}

// Geometry metrics against spot.obj in the frame the views were rendered in, so offsets and scale
// errors count.
EvalReport spot_geometry(const Mesh& mesh) {
  EvalOptions options;
  options.normalize = false;
  options.gt_render_fill = 0.9f;  // `unique3d render`'s default, which made examples/spot/views
  options.surface_samples = 50000;
  options.fscore_thresholds = {0.005f, 0.01f};
  options.appearance = false;
  const EvalReport report = evaluate_meshes(mesh, read_mesh(kSpot / "spot.obj"), options);
  std::printf(
      "spot: Chamfer-L1 %.5f (accuracy %.5f, completeness %.5f), F-score@0.005 %.4f (P %.4f R %.4f), "
      "F-score@0.01 %.4f, volume IoU %.4f\n",
      report.chamfer.chamfer_l1, report.chamfer.accuracy, report.chamfer.completeness, report.fscores[0].fscore,
      report.fscores[0].precision, report.fscores[0].recall, report.fscores[1].fscore, report.iou.iou);
  return report;
}

// Mean over the four views of the PSNR of the mesh rendered from the view (its own colours, no
// lighting, as `unique3d render` rendered the inputs) against the input colour image, both on white.
double rendered_back_psnr(const Mesh& mesh, const ViewSet& views) {
  RenderSettings settings;
  settings.ssaa = 2;  // as the inputs were rendered
  double sum = 0;
  for (View v : kAllViews) {
    const Image& input = views[v].rgb;
    const RenderedView r = render_view(mesh, view_camera(v, input.width), settings);
    const double p = psnr(composite_on_white(r.rgb), composite_on_white(input));
    std::printf("spot rendered back, %s view: PSNR %.2f dB\n", view_name(v), p);
    sum += p;
  }
  return sum / 4;
}

TEST(BundledExample, SpotReconstructsClosedTexturedAndOnTheSilhouettes) {
  set_progress_quiet(true);
  const ViewSet views = load_view_set(kSpot / "views");
  const ReconstructResult result = reconstruct(views, shortened_options());
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

  const EvalReport report = spot_geometry(mesh);
  // Measured: Chamfer-L1 0.00240, F-score@0.005 0.909. Bounds about 45 % and 0.06 worse; with 1 coarse
  // and 1 refinement step the fitted mesh gives 0.0165 and 0.305.
  EXPECT_LT(report.chamfer.chamfer_l1, 0.0035);
  EXPECT_GT(report.fscores[0].fscore, 0.85);
  const double p = rendered_back_psnr(mesh, views);
  std::printf("spot rendered back: mean PSNR %.2f dB\n", p);
  // Measured: 28.79 dB (front 31.3, right 26.8, back 28.7, left 28.4); with 1 + 1 steps 27.20 dB.
  EXPECT_GT(p, 28.0);
}

// Without the silhouette fit the optimisation alone places the surface.
TEST(BundledExample, SpotWithoutTheSilhouetteFitMatchesTheGroundTruth) {
  set_progress_quiet(true);
  ReconstructOptions options = shortened_options();
  options.silhouette_fit.enabled = false;
  options.color_mode = ColorMode::Vertex;  // only the geometry is measured here
  const EvalReport report = spot_geometry(reconstruct(load_view_set(kSpot / "views"), options).mesh);
  // Measured: Chamfer-L1 0.00240, F-score@0.005 0.910; with 1 coarse and 1 refinement step 0.0352 and
  // 0.162. Bounds as above.
  EXPECT_LT(report.chamfer.chamfer_l1, 0.0035);
  EXPECT_GT(report.fscores[0].fscore, 0.85);
}

TEST(BundledExample, ReconstructionIsDeterministic) {
  set_progress_quiet(true);
  const ViewSet views = load_view_set(kSpot / "views");
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
