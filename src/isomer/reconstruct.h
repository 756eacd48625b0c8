#pragma once
// ISOMER, the whole reconstruction from a view set to a coloured mesh, as a fixed sequence of stages
// (paper Sec. 3.2, official `geo_reconstruct`):
//   1. initial mesh            (initial_mesh.h; or a sphere, or the visual hull: visual_hull.h)
//   2. coarse optimisation     (coarse_stage.h: fit normals and masks at 512 px)
//   3. refinement              (refine_stage.h: ExplicitTarget normals, rendered at up to 512 px)
//   4. smooth and subdivide    (surface_cleanup.h)
//   5. colouring               (explicit_target.h: ExplicitTarget + completion)
// Each stage is a function of the mesh so far; reconstruct() runs them in order and times each. The
// result is in the views' world frame; the official release's output scale is applied when writing
// (pipeline/reconstruct.h).
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/view_set.h"
#include "isomer/coarse_stage.h"
#include "isomer/explicit_target.h"
#include "isomer/initial_mesh.h"
#include "isomer/normal_views.h"
#include "isomer/refine_stage.h"
#include "isomer/surface_cleanup.h"
#include "core/view_set.h"
#include "isomer/visual_hull.h"

namespace u3d {

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
  ColoringOptions coloring;
};

struct ReconstructResult {
  Mesh mesh;
  std::vector<StageTiming> timings;
  StageReport coarse, refine;  // the optimisation stages' loss and time profile (when they ran)
  ColoringReport coloring;
};

// Stage 1: the initial mesh, the sphere or the visual hull, as the options choose.
Mesh stage_initial_mesh(const ViewSet& views, const ReconstructOptions& options);

ReconstructResult reconstruct(const ViewSet& views, const ReconstructOptions& options = {});

}  // namespace u3d
