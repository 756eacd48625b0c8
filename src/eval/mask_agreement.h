#pragma once
// Where a reconstruction disagrees with the masks of the views it was made from (issue 40): geometry a
// view shows over background (a band bridging a gap, a sliver), and parts of a mask the mesh leaves
// uncovered. A silhouette IoU cannot see a thin band (spot's 135-pixel band between the horns left it
// at 0.988); counting the pixels beyond a tolerance, and how they group, can.
//
// Per view the mesh is rasterized through the view's own camera at its mask's resolution (pixel
// centres, as the rasterizer covers them); the mask is the normal map's (alpha >= 0.5, the mask ISOMER
// fits). A mesh pixel is spurious when its centre lies farther than `tolerance_px` from every mask
// pixel's centre (Euclidean), a mask pixel missing when it lies that far from every mesh pixel; each
// kind is grouped into blobs (8-connected). The mesh must be in the views' frame (what `reconstruct`
// writes unless asked for the official output scale).
//
// Pieces: the mesh's connected pieces (vertices at identical positions welded, as a UV seam splits
// them) against those of the masks' visual hull, the voxels of a grid over the views' box [-1, 1]^3
// whose centres project inside every mask, 6-connected. A mesh with more pieces than the hull has a
// piece no view asks for, or has broken one the masks hold together.
#include <array>

#include "core/mesh.h"
#include "core/view_set.h"

namespace u3d {

struct MaskAgreementOptions {
  float tolerance_px = 2.f;
  int hull_resolution = 256;  // voxels per axis of the hull's grid
};

// Pixels of one kind in one view, and how they group.
struct PixelBlobs {
  size_t pixels = 0;
  size_t blobs = 0;         // 8-connected groups
  size_t largest_blob = 0;  // pixels of the largest group
};

struct ViewMaskAgreement {
  size_t mask_pixels = 0;
  size_t mesh_pixels = 0;
  PixelBlobs spurious;  // mesh pixels farther than the tolerance from the mask: geometry over background
  PixelBlobs missing;   // mask pixels farther than the tolerance from the mesh: parts the mesh lacks
};

struct MaskAgreement {
  MaskAgreementOptions options;
  std::array<ViewMaskAgreement, 4> views;  // indexed by int(View)
  int mesh_components = 0;
  int hull_components = 0;
};

MaskAgreement mask_agreement(const Mesh& mesh, const ViewSet& views, const MaskAgreementOptions& options = {});

// The per-view part alone: `mesh_pixels` and `mask_pixels` are coverage images of one size (non-zero
// = covered).
ViewMaskAgreement compare_coverage(const std::vector<uint8_t>& mesh_pixels, const std::vector<uint8_t>& mask_pixels,
                                   int width, int height, float tolerance_px);

// Connected pieces of the voxels of a `resolution`^3 grid over [-1, 1]^3 whose centres project inside
// every view's normal-map mask (6-connected).
int visual_hull_components(const ViewSet& views, int resolution);

}  // namespace u3d
