#include "eval/evaluate.h"

#include <algorithm>

#include "core/error.h"
#include "core/progress.h"
#include "render/shade.h"

namespace u3d {

namespace {

MeshSummary summarize(const Mesh& mesh) {
  return {mesh.vertex_count(), mesh.face_count(), has_color_information(mesh), diagnose_mesh(mesh)};
}

}  // namespace

EvalReport evaluate_meshes(Mesh pred, Mesh gt, const EvalOptions& options, const ViewSet* input_views) {
  pred.validate("predicted mesh");
  gt.validate("ground-truth mesh");
  require(options.surface_samples >= 100, "at least 100 surface samples are needed, got " +
                                               std::to_string(options.surface_samples));
  for (float t : options.fscore_thresholds)
    require(t > 0, "F-score thresholds must be positive, got " + std::to_string(t));
  EvalReport r;
  r.options = options;
  if (input_views) {
    StageTimer timer("agreement with the input masks");
    r.mask_agreement = mask_agreement(pred, *input_views, options.mask_agreement);
  }
  if (input_views && options.appearance) {
    StageTimer timer("PSNR in the input views");
    r.input_view_psnr = input_view_psnr(pred, *input_views, options.appearance_options.ssaa);
    r.appearance_seconds += timer.finish();
  }
  require(options.gt_render_fill >= 0, "render fill must not be negative");
  require(options.gt_render_fill == 0 || !options.normalize,
          "placing the GT in a render frame only makes sense in the shared frame");
  if (options.normalize) {
    normalize_to_unit_box(pred, 0.5f);
    normalize_to_unit_box(gt, 0.5f);
  } else {
    if (options.gt_render_fill > 0) normalize_to_unit_box(gt, options.gt_render_fill);
    Similarity s = normalize_to_unit_box(gt, 0.5f);
    for (auto& p : pred.positions) p = s.scale * (p + s.offset);
  }
  r.pred = summarize(pred);
  r.gt = summarize(gt);
  for (const auto& w : mesh_warnings(r.pred.diagnostics, "predicted mesh")) r.warnings.push_back(w);
  for (const auto& w : mesh_warnings(r.gt.diagnostics, "ground-truth mesh")) r.warnings.push_back(w);

  StageTimer geometry_timer("geometry metrics");
  SurfaceDistances distances = surface_distances(pred, gt, options.surface_samples, options.seed);
  r.chamfer = chamfer_distance(distances);
  for (float t : options.fscore_thresholds) r.fscores.push_back(fscore(distances, t));
  const std::vector<uint8_t> visible = visible_from_outside(gt, distances.gt_samples, options.visibility);
  r.gt_hidden_samples = size_t(std::count(visible.begin(), visible.end(), uint8_t(0)));
  const SurfaceDistances seen = keep_gt_samples(distances, visible);
  r.chamfer_visible = chamfer_distance(seen);
  for (float t : options.fscore_thresholds) r.fscores_visible.push_back(fscore(seen, t));
  r.iou = volume_iou(pred, gt, options.iou_resolution);
  if (r.iou.union_cells == 0) r.warnings.push_back("neither mesh encloses any volume: volume IoU is reported as 0");
  r.geometry_seconds = geometry_timer.finish();

  if (options.appearance) {
    if (!r.pred.has_color) r.warnings.push_back("predicted mesh has no colour: it is rendered mid-gray");
    if (!r.gt.has_color) r.warnings.push_back("ground-truth mesh has no colour: it is rendered mid-gray");
    StageTimer appearance_timer("appearance metrics (24 views)");
    r.appearance = appearance_metrics(pred, gt, options.appearance_options, options.save_renders_dir);
    r.appearance_seconds += appearance_timer.finish();
  }
  return r;
}

}  // namespace u3d
