#pragma once
// ISOMER stage 1 (official reconstruct_stage1): from an initial mesh, fit the four normal maps and
// their masks with the differentiable normal renderer and the continuous-remeshing optimizer, shrinking
// the edge length from start to end. Losses: normal L2 where the mesh is rendered, alpha L2 where the
// target is background, expansion along normals (paper Fig. 5b) and an out-of-box penalty.
#include "core/mesh.h"
#include "isomer/normal_views.h"
#include "isomer/stage_report.h"

namespace u3d {

struct CoarseStageOptions {
  int steps = 200;
  float start_edge_length = 0.1f;
  float end_edge_length = 0.02f;
  float gain = 0.05f;             // edge-length controller gain
  float learning_rate = 0.3f;
  float lr_decay = 0.995f;        // learning rate multiplied by this before every step
  float expansion_weight = 0.1f;
  float out_of_box_limit = 0.99f;
  float out_of_box_weight = 10.f;
  // Longest side the views are rendered at (0 = the maps' own). The official renders at the maps'
  // 512 px; 256 px keeps edges of 0.02 (the end length) at 2.5 px and quarters the pixel work.
  int render_resolution = 256;
  unsigned seed = 1;

  // Schedules of the official pipeline: starting from the fast initial mesh ("std"), or from a sphere.
  static CoarseStageOptions from_initial_mesh() { return {}; }
  static CoarseStageOptions from_sphere();
};

// The sphere initialisation: an icosphere of radius 0.5 (about 640 faces).
Mesh sphere_initial_mesh();

// Fits the geometry of `initial` (its colours are ignored) to the views; the result has positions and
// faces only.
Mesh run_coarse_stage(const Mesh& initial, const NormalViews& views, const CoarseStageOptions& options = {},
                      StageReport* report = nullptr);

}  // namespace u3d
