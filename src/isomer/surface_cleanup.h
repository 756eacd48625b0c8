#pragma once
// The clean-up the official pipeline applies right before colouring (docs/official_reference.md
// 4.1): one uniform Laplacian smoothing step, non-manifold repair, and Loop subdivision so that
// vertex colours have enough vertices to carry the image detail.
//
// pymeshlab subdivides only edges longer than 0.25 % of the bounding-box diagonal; our Loop
// subdivision (isomer/loop_subdivision.h) is uniform, so here an iteration runs only while the mean
// edge length is above that threshold (a coarse mesh gets both iterations, an already fine one none)
// and the face budget allows it.
#include "core/mesh.h"

namespace u3d {

struct SurfaceCleanupOptions {
  int smooth_iterations = 1;              // official: 1 step
  int subdivision_iterations = 2;         // official: 2
  float subdivision_threshold = 0.0025f;  // fraction of the bounding-box diagonal (official 0.25 %)
  // Pieces with fewer faces are crumbs that remeshing and repair can leave (a 2-face "pillow", a
  // 6-face bipyramid): too small for any view to colour, and Loop subdivision turns them non-manifold.
  int min_component_faces = 20;
  // A step that would pass this many faces is skipped. The official caps the refined mesh at 1e6
  // vertices, so its edges end near the threshold and subdivision adds little; our refinement stops
  // splitting at 20k vertices, and two uniform steps gave 650k faces (a 20 MB GLB) for no visible
  // colour gain over one.
  size_t max_faces = 300000;
};

// Uniform Laplacian step as pymeshlab's: each vertex moves to the mean of itself and its neighbours.
void smooth_uniform_laplacian(Mesh& mesh, int iterations);

Mesh smooth_and_subdivide(const Mesh& mesh, const SurfaceCleanupOptions& options = {});

}  // namespace u3d
