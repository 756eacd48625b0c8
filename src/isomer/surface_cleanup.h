#pragma once
// The clean-up the official pipeline applies right before colouring (docs/official_reference.md
// 4.1): one uniform Laplacian smoothing step, non-manifold repair, and Loop subdivision so that
// vertex colours have enough vertices to carry the image detail.
//
// pymeshlab subdivides only edges longer than 0.25 % of the bounding-box diagonal; Open3D's Loop
// subdivision is uniform, so here an iteration runs only while the mean edge length is above that
// threshold (a coarse mesh gets both iterations, an already fine one none).
#include "core/mesh.h"

namespace u3d {

struct SurfaceCleanupOptions {
  int smooth_iterations = 1;              // official: 1 step
  int subdivision_iterations = 2;         // official: 2
  float subdivision_threshold = 0.0025f;  // fraction of the bounding-box diagonal (official 0.25 %)
  // Pieces with fewer faces are crumbs that remeshing and repair can leave (a 2-face "pillow", a
  // 6-face bipyramid): too small for any view to colour, and Loop subdivision turns them non-manifold.
  int min_component_faces = 20;
};

// Uniform Laplacian step as pymeshlab's: each vertex moves to the mean of itself and its neighbours.
void smooth_uniform_laplacian(Mesh& mesh, int iterations);

Mesh smooth_and_subdivide(const Mesh& mesh, const SurfaceCleanupOptions& options = {});

}  // namespace u3d
