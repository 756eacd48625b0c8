#pragma once
// Makes a closed mesh agree with the four input masks (issue 14: thin plates, open bays, separate
// parts). The normal-integration initial mesh can bridge a frame's open bays, lose a plate whose front
// and back sheets cross, or drop a small separate part; the optimisation stages cannot change the
// topology back. The masks alone bound the object by its visual hull (visual_hull.h), so on a grid
//     solid = hull AND (mesh OR from_hull),
// where a grid column (along z for the front and back views, along x for the sides) is taken from
// the hull when the hull reaches into it but `hull AND mesh` does not (fewer than 2 samples): there
// the mesh misses part of a mask. It is also taken from the hull when `hull AND mesh` fills at least
// 30 % of the hull's samples in it: mesh and hull agree there but for a dent or a thinned plate.
// Everything the mesh adds outside the masks is cut away, and every pixel of every mask is covered
// again, so the result's silhouettes are those of the hull. Elsewhere (the hull far deeper than the
// mesh: a concavity) the mesh is kept, up to the grid's resolution.
//
// The mesh's inside comes from column_occupancy.h (the region between crossed plate sheets counts as
// inside), the surface from marching tetrahedra on the combined field, and quadric decimation brings
// it to the requested face count, closed and manifold.
#include "core/mesh.h"
#include "core/view_set.h"
#include "geometry/marching_tetrahedra.h"

namespace u3d {

struct SilhouetteFitOptions {
  bool enabled = true;
  // A mesh is fitted only when its silhouette IoU against the masks (silhouette_check.h) is below
  // these in some view; where it agrees with them it is kept as it is (the grid would only blur its
  // detail and cost time). The initial mesh is fitted only when it misses most of a mask (table 0.04,
  // box_chair 0.24): the real objects' initial meshes are often off on a side view (hand 0.37, spot
  // 0.71, cat 0.79), the optimisation repairs that, and fitting them made hand 7 % worse.
  float initial_min_iou = 0.3f;
  float final_min_iou = 0.95f;
  // Voxels per axis over the views' box [-1, 1]^3: for the initial mesh, and for the optimised mesh
  // (finer, as its detail is kept at this resolution). 192 gives a plate of 2 % of a 1.8-unit object
  // about 3.5 voxels, 256 about 4.6.
  int resolution = 192;
  int final_resolution = 256;
  int final_faces = 50000;  // the fitted optimised mesh is decimated to this
};

// The combined field on the visual hull's grid layout (visual_hull_field), positive inside.
ScalarGrid silhouette_fit_field(const Mesh& mesh, const ViewSet& views, int resolution);

// The smallest of the four views' silhouette IoUs of `mesh` against the masks.
float min_silhouette_iou(const Mesh& mesh, const ViewSet& views);

// The fitted mesh on a grid of `resolution` voxels per axis, with at most `target_faces` faces
// (closed, manifold, outward). Throws Error if `mesh` is not closed or the masks share no volume.
Mesh fit_to_silhouettes(const Mesh& mesh, const ViewSet& views, int resolution, size_t target_faces);

}  // namespace u3d
