#pragma once
// Makes a mesh agree with the four input masks (issue 14: thin plates, open bays, separate parts). The
// normal-integration initial mesh can bridge a frame's open bays, lose a plate whose front and back
// sheets cross, or drop a small separate part; the optimisation can sag or perforate a plate that the
// views see only edge-on; smoothing thins plates out. Continuous remeshing cannot change the topology
// back. The masks alone bound the object by its visual hull (visual_hull.h); the mesh adds what each
// view sees in front of it. On the hull's grid
//     solid = hull AND NOT (space some view sees in front of the mesh),
// the largest shape that fits the masks and looks from each of the four views as the mesh does. A
// sample is carved by a view when it lies in front of the mesh's nearest surface through its pixel
// (the field is that depth difference, so the surface passes where the mesh's visible surface is),
// except on the ray of a mask pixel the mesh leaves uncovered (a part the mesh lacks: no view may carve
// where it belongs). So a hole or a dent no view sees (a perforated or sagging table top) is filled
// from the hull, crossed plate sheets become one plate between the outermost sheets, an open bay the
// mask shows stays open, and excess outside the masks is cut. Last, a grid column (along z for the
// front and back views, along x for the sides) that the carving left with fewer than 2 samples is
// taken from the hull: every pixel of every mask is covered again.
//
// The surface comes from marching tetrahedra on that field, and quadric decimation brings it to the
// requested face count, closed and manifold. The mesh itself may be open or self-intersecting: only its
// depth as each view sees it is used.
//
// That whole-object fit replaces every part of the surface by the grid's carving, detail included. An
// optimised mesh that keeps its volume but leaves a mask (a thin part off a mask, a part it lacks) is
// therefore fitted locally (issue 40): its own signed distance, repaired by the masks' hull only within a
// few voxels of where the masks contradict it (local_fit_field).
#include <optional>

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
  // 0.71, cat 0.79), the optimisation repairs that, and fitting them made hand 7 % worse. The final
  // check is on the smoothed and subdivided mesh (what would be output); the fit starts from the
  // optimised mesh before smoothing.
  float initial_min_iou = 0.3f;
  // An initial mesh with more pieces than the masks' visual hull (on a grid of pieces_resolution) is
  // joined and cut by that hull (start_for_extra_pieces): screened Poisson can join parts across a gap
  // the masks show open and cut them off where the masks hold them together (spot's horns: one piece
  // with a band across the gap between them, floating above the head; human_man's hands). Remeshing
  // keeps the pieces, so the band survived the optimisation as a wire over the background (134 pixels
  // of the bundled example's front view) and the horns as a piece of their own. Fitting that mesh
  // instead (fit_to_silhouettes) keeps its depth but threads it with tunnels along the rays of the mask
  // pixels it misses (Euler characteristic -30 to -148 on spot at 64^3 to 192^3); starting from the hull
  // itself loses the Poisson surface's detail (spot 4 % worse in CD-L1 than without any fit)
  // (docs/evaluation.md, "Geometry over the background"). 64 is the Poisson surface's own resolution
  // (depth 6).
  int pieces_resolution = 64;
  float final_min_iou = 0.97f;
  // Voxels per axis over the views' box [-1, 1]^3: for the initial mesh, and for the optimised mesh
  // (finer, as its detail is kept at this resolution). 192 gives a plate of 2 % of a 1.8-unit object
  // about 3.5 voxels, 256 about 4.6.
  int resolution = 192;
  int final_resolution = 256;
  int final_faces = 50000;  // the fitted optimised mesh is decimated to this
  // The optimised mesh is also fitted when its volume is below this share of the carved hull's,
  // measured on a grid of check_resolution; fitted whole then (the hidden volume it lost is repaired
  // from the carving), and only locally when it holds this share and leaves a mask (fit_locally).
  float min_fill = 0.8f;
  int check_resolution = 128;
  // Below this share the optimised mesh has lost most of its volume (a sagged or perforated plate:
  // table 19-22 %, shelf 14-16 % at 512 and 2048 px; box_chair 55-64 %, signpost 71-74 %), its depth
  // is no account of the object, and the masks' hull is taken without fitting.
  float hull_below_fill = 0.5f;
};

// The combined field on the visual hull's grid layout (visual_hull_field), positive inside.
ScalarGrid silhouette_fit_field(const Mesh& mesh, const ViewSet& views, int resolution);

// The mesh's volume as a share of the carved hull's (the field above at `resolution`): well below 1
// when the mesh has lost volume that no view shows missing (a sagging or perforated plate seen only
// edge-on). Empty when the mesh is not closed.
std::optional<float> carved_hull_fill(const Mesh& mesh, const ViewSet& views, int resolution);

// The smallest of the four views' silhouette IoUs of `mesh` against the masks.
float min_silhouette_iou(const Mesh& mesh, const ViewSet& views);

// Mean angle in degrees between the mesh's face normals and the views' normal maps, over the pixels
// both cover: how well a candidate explains the normal maps (180 when they share no pixel).
float normal_map_error(const Mesh& mesh, const ViewSet& views);

// A start for an initial mesh with more pieces than the masks' hull (on a grid of
// options.pieces_resolution); empty when it has no more. On that grid, the mesh's own signed distance,
// its pieces joined across gaps of up to two samples between them (closed by a cube there, within four
// samples of the gap) and cut by the hull, decimated to `target_faces`: the mesh's surface is kept but
// where the masks contradict it or it falls apart. When that still has more pieces than the hull, the
// hull itself. Reports the pieces as a progress message.
std::optional<Mesh> start_for_extra_pieces(const Mesh& initial, const ViewSet& views,
                                           const SilhouetteFitOptions& options, size_t target_faces);

// The visual hull of the normal maps' masks on a grid of `resolution`, decimated to `target_faces`.
Mesh silhouette_hull(const ViewSet& views, int resolution, size_t target_faces);

// The final check and fit of an optimised mesh (reconstruct.h, stage 4b); `smoothed` is the mesh as it
// would be output. Empty when the smoothed mesh keeps every mask (IoU >= final_min_iou) and the
// optimised mesh holds at least min_fill of the carved hull's volume. Otherwise the masks' hull when the
// mesh holds less than hull_below_fill. Else, when the mesh holds at least min_fill and the smoothed mesh
// is closed, the local fit of the smoothed mesh (fit_locally), otherwise the whole fitted optimised
// mesh; that or the hull, whichever explains the normal maps better (normal_map_error). Reports its
// measures as progress messages.
std::optional<Mesh> fit_optimised_mesh(const Mesh& optimised, const Mesh& smoothed, const ViewSet& views,
                                       const SilhouetteFitOptions& options);

// Removes the pieces of `mesh` that no view needs: every pixel a piece covers, in every view, another
// piece covers too. The silhouette fit's grid leaves such crumbs where hull columns are put back next
// to a carved part (signpost: four of 22 to 124 faces in front of its pole, against the masks' two
// pieces); reconstruct() removes them from a grid surface it outputs, once decimated.
void drop_pieces_no_view_needs(Mesh& mesh, const ViewSet& views);

// The fitted mesh on a grid of `resolution` voxels per axis, with at most `target_faces` faces
// (closed, manifold, outward). Throws Error if the masks share no volume.
Mesh fit_to_silhouettes(const Mesh& mesh, const ViewSet& views, int resolution, size_t target_faces);

// The local fit (issue 40): the signed distance of `surface` (closed: the optimised mesh as it would be
// output), repaired only near the samples where the masks contradict it: inside the surface but a
// voxel or more outside a mask (cut by the masks' hull), or outside the surface on the ray of a mask
// pixel it leaves uncovered, a voxel or more inside every mask (a part it lacks: joined by the hull
// there, as the whole fit does). Within 4 samples of those the repaired field is blended linearly into
// the surface's own; beyond, the surface is kept, detail that no view sees (a pit in a top) included.
// Same layout and units as silhouette_fit_field.
ScalarGrid local_fit_field(const Mesh& surface, const ViewSet& views, int resolution);

// The surface of local_fit_field, decimated to at most `target_faces` faces (closed, manifold, outward).
Mesh fit_locally(const Mesh& surface, const ViewSet& views, int resolution, size_t target_faces);

}  // namespace u3d
