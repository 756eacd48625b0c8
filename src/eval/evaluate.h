#pragma once
// The whole evaluation of a predicted mesh against ground truth (docs/evaluation.md): frame
// normalization, geometry metrics (Chamfer, F-score, volume IoU), appearance metrics (PSNR, SSIM) and,
// given the views the prediction was reconstructed from, its agreement with their masks and its PSNR
// against their RGB images.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "eval/appearance.h"
#include "eval/chamfer.h"
#include "eval/fscore.h"
#include "eval/input_view_psnr.h"
#include "eval/mask_agreement.h"
#include "eval/mesh_checks.h"
#include "eval/visible_surface.h"
#include "eval/volume_iou.h"

namespace u3d {

struct EvalOptions {
  // true: each mesh is centred and scaled on its own so its longest bounding-box side spans
  // [-0.5, 0.5] (the paper's protocol: pose and scale errors of the prediction are forgiven).
  // false ("shared frame"): the meshes are taken to share one frame, as reconstructions from known
  // views do; the similarity that normalizes the GT is applied to both, so distances keep the same
  // units as above while offsets and scale errors of the prediction count.
  bool normalize = true;
  // Shared frame only: when > 0, the GT is first placed as `unique3d render --fill F` placed it
  // before rendering the views (the frame a reconstruction from those views comes out in).
  float gt_render_fill = 0;
  size_t surface_samples = 100000;  // per mesh
  std::vector<float> fscore_thresholds{0.01f, 0.02f, 0.05f};
  VisibilityOptions visibility;  // which GT samples count as visible, for the visible-surface metrics
  int iou_resolution = 64;
  bool appearance = true;
  AppearanceOptions appearance_options;
  MaskAgreementOptions mask_agreement;  // with input views only
  std::string save_renders_dir;  // empty: renders are not written
  uint64_t seed = 0;
};

struct MeshSummary {
  size_t vertices = 0;
  size_t faces = 0;
  bool has_color = false;
  MeshDiagnostics diagnostics;
};

struct EvalReport {
  EvalOptions options;
  MeshSummary pred, gt;
  ChamferDistance chamfer;
  std::vector<FScore> fscores;  // one per threshold
  // The same two with only the GT samples visible from outside (eval/visible_surface.h): precision and
  // accuracy are unchanged, completeness and recall leave out GT surface no camera can see.
  size_t gt_hidden_samples = 0;
  ChamferDistance chamfer_visible;
  std::vector<FScore> fscores_visible;
  VolumeIou iou;
  std::optional<AppearanceMetrics> appearance;
  std::optional<MaskAgreement> mask_agreement;  // with input views only
  std::optional<InputViewPsnr> input_view_psnr;  // with input views and appearance only (ssaa of appearance_options)
  std::vector<std::string> warnings;
  double geometry_seconds = 0;
  double appearance_seconds = 0;
};

// Throws Error when a mesh is empty or invalid; imperfect meshes (open, degenerate faces, no colour)
// are evaluated and reported in `warnings`. `input_views` (optional): the views `pred` was
// reconstructed from, in whose frame it lies; then `mask_agreement` and, with appearance,
// `input_view_psnr` are measured (before any frame transform).
EvalReport evaluate_meshes(Mesh pred, Mesh gt, const EvalOptions& options, const ViewSet* input_views = nullptr);

}  // namespace u3d
