#pragma once
// ISOMER, the whole reconstruction from a view set to a coloured mesh, as a fixed sequence of stages
// (paper Sec. 3.2, official `geo_reconstruct`):
//   1. initial mesh            (initial_mesh.h; or a sphere, or the visual hull: visual_hull.h)
//   2. coarse optimisation     (coarse_stage.h: fit normals and masks at 512 px)
//   3. refinement              (refine_stage.h: ExplicitTarget normals, rendered at up to 512 px)
//   4. smooth and subdivide    (surface_cleanup.h)
//   5. colouring               (explicit_target.h: ExplicitTarget + completion)
//   6. output transform        (identity, or the official release's scale)
// Each stage is a function of the mesh so far; reconstruct() runs them in order and times each.
#include <string>
#include <vector>

#include "core/mesh.h"
#include "isomer/coarse_stage.h"
#include "isomer/explicit_target.h"
#include "isomer/initial_mesh.h"
#include "isomer/refine_stage.h"
#include "isomer/surface_cleanup.h"
#include "isomer/view_set.h"
#include "isomer/visual_hull.h"

namespace u3d {

// The official app writes 0.675 * p (conventions.md 2.0: scale 1.35 / 2, no rotation).
inline constexpr float kOfficialOutputScale = 0.675f;

// Longest side of the normal maps the coarse stage receives (official: 512); the stage may render
// lower still (CoarseStageOptions::render_resolution).
inline constexpr int kCoarseMapResolution = 512;

struct ReconstructOptions {
  InitialMeshOptions init;
  bool sphere_init = false;  // start the coarse stage from a sphere instead of the initial mesh
  bool visual_hull = false;  // start from the hull carved from the masks (the baseline: with both stages off)
  VisualHullOptions hull;
  bool run_coarse = true;
  bool run_refine = true;
  CoarseStageOptions coarse;  // with sphere_init, CoarseStageOptions::from_sphere() is the official schedule
  RefineStageOptions refine;  // refine.use_explicit_target = false: plain multi-view normal loss
  SurfaceCleanupOptions cleanup;
  ColouringOptions colouring;
  bool official_output_scale = false;  // false: the views' world frame, unscaled
};

struct StageTiming {
  std::string name;
  double seconds = 0.0;
};

struct ReconstructResult {
  Mesh mesh;
  std::vector<StageTiming> timings;
  StageReport coarse, refine;  // the optimisation stages' loss and time profile (when they ran)
  ColouringReport colouring;
};

// The optimisation stages' input: each view's world-space normal map encoded as (n + 1) / 2 with the
// mask as alpha, and its camera.
struct StageViews {
  std::vector<Image> normal_maps;
  std::vector<Camera> cameras;
};
StageViews stage_views(const ViewSet& views);

// The stages, in pipeline order.
Mesh stage_initial_mesh(const ViewSet& views, const ReconstructOptions& options);
Mesh stage_coarse(const Mesh& mesh, const StageViews& views, const ReconstructOptions& options,
                  StageReport* report = nullptr);
Mesh stage_refine(const Mesh& mesh, const StageViews& views, const ReconstructOptions& options,
                  StageReport* report = nullptr);
Mesh stage_smooth_and_subdivide(const Mesh& mesh, const ReconstructOptions& options);
ColouringReport stage_colouring(Mesh& mesh, const ViewSet& views, const ReconstructOptions& options);
void stage_output_transform(Mesh& mesh, const ReconstructOptions& options);

ReconstructResult reconstruct(const ViewSet& views, const ReconstructOptions& options = {});

}  // namespace u3d
