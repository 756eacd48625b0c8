#pragma once
// ISOMER, the whole reconstruction from a view set to a coloured mesh, as a fixed sequence of stages
// (paper Sec. 3.2, official `geo_reconstruct`):
//   1. initial mesh            (initial_mesh.h; fitted to the masks by silhouette_fit.h when it misses
//                               most of a mask, the masks' hull when it has more pieces than that hull;
//                               or a sphere, or the visual hull: visual_hull.h)
//   2. coarse optimisation     (coarse_stage.h: fit normals and masks at 512 px)
//   3. refinement              (refine_stage.h: view or ExplicitTarget normals, at up to 512 px)
//   4. smooth and subdivide    (surface_cleanup.h)
//   4b. silhouette fit         (silhouette_fit.h, fit_optimised_mesh: only when the smoothed mesh
//                               leaves a mask or the optimised mesh has lost volume the views do not
//                               show missing; then the fitted optimised mesh or the masks' hull, not
//                               smoothed)
//   5. decimation to a face count (geometry/quadric_decimation.h; only when asked, or for textures);
//      a surface from the fit's grid then loses the pieces no view needs (drop_pieces_no_view_needs)
//   6. colouring               (explicit_target.h: ExplicitTarget + completion, per vertex), or
//      texture baking          (texture_bake.h: UV atlas, the same colouring per texel)
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
#include "isomer/silhouette_fit.h"
#include "isomer/surface_cleanup.h"
#include "isomer/texture_bake.h"
#include "isomer/visual_hull.h"

namespace u3d {

// Longest side of the normal maps the coarse stage receives (official: 512); the stage may render
// lower still (CoarseStageOptions::render_resolution).
inline constexpr int kCoarseMapResolution = 512;

// How the colour is stored: per vertex, or in a baked texture with UVs.
enum class ColorMode { Vertex, Texture };

// Face count of a textured result when none is asked for (as Hunyuan3D-2's face reducer).
inline constexpr size_t kDefaultTextureFaces = 40000;

struct ReconstructOptions {
  InitialMeshOptions init;
  SilhouetteFitOptions silhouette_fit;  // applied to the initial mesh (not to the sphere or the hull)
  bool sphere_init = false;  // start the coarse stage from a sphere instead of the initial mesh
  bool visual_hull = false;  // start from the hull carved from the masks (the baseline: with both stages off)
  VisualHullOptions hull;
  bool run_coarse = true;
  bool run_refine = true;
  CoarseStageOptions coarse;  // with sphere_init, CoarseStageOptions::from_sphere() is the official schedule
  RefineStageOptions refine;  // refine.target: which normals the refinement fits (refine_stage.h)
  SurfaceCleanupOptions cleanup;
  // Final face count: the cleaned-up mesh is decimated to it (quadric, staying closed and manifold)
  // when it has more. 0: kDefaultTextureFaces with ColorMode::Texture, no decimation with vertex colours.
  size_t faces = 0;
  ColorMode color_mode = ColorMode::Texture;
  ColoringOptions coloring;  // weights, masks and threshold of both modes
  TextureBakeOptions texture;
};

// The face count `options` ask for after the clean-up (0: keep the mesh as it is).
size_t final_face_count(const ReconstructOptions& options);

struct ReconstructResult {
  Mesh mesh;
  std::vector<StageTiming> timings;
  StageReport coarse, refine;  // the optimisation stages' loss and time profile (when they ran)
  ColoringReport coloring;
  TextureBakeReport texture;  // with ColorMode::Texture
};

// Stage 1: the initial mesh, the sphere or the visual hull, as the options choose. `fitted` (if given)
// says whether the initial mesh was replaced by a grid surface (fitted to the masks, or their hull).
Mesh stage_initial_mesh(const ViewSet& views, const ReconstructOptions& options, bool* fitted = nullptr);

ReconstructResult reconstruct(const ViewSet& views, const ReconstructOptions& options = {});

}  // namespace u3d
