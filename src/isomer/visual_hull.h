#pragma once
// The visual hull of the four views: the largest shape whose silhouettes fit inside all four masks,
// a baseline that uses the masks only (no normals). docs/evaluation.md compares it with ISOMER.
//
// Carving. A grid of resolution^3 voxels spans the views' orthographic box [-1, 1]^3. At each voxel
// centre the field is the minimum over the four views of the mask's signed distance to its outline
// (positive inside, pixels next to the outline placed within their pixel by alpha - 0.5), read
// bilinearly at the centre's projection through the view's own camera (view_camera), in units of
// 0.5 per voxel and clamped to +-1. So a centre is kept exactly when it projects inside every mask,
// and the surface crosses between two samples where the mask's edge is even when a voxel spans
// several pixels (alpha itself, flat a pixel away from the edge, put it halfway). One layer of outside
// samples surrounds the grid, so an object touching the box still gives a closed surface.
//
// Surface. The zero level set of the field (marching_tetrahedra.h): closed, manifold, outward
// normals. It has about a million faces at resolution 256; quadric decimation (quadric_decimation.h)
// brings it to `target_faces`, still closed and manifold.
#include "core/mesh.h"
#include "core/view_set.h"
#include "geometry/marching_tetrahedra.h"

namespace u3d {

struct VisualHullOptions {
  int resolution = 256;      // voxels per axis over [-1, 1]^3
  int target_faces = 50000;  // after decimation; 0 keeps the extracted surface as it is
};

// Which alpha channel is the mask: the RGB images' (the baseline, as rendered) or the normal maps'
// (the masks the initial mesh and silhouette_check.h use; the same as the RGB alpha unless the RGB
// images come without one).
enum class HullMasks { Rgb, Normals };

// The carved field, (resolution + 2)^3 samples including the outside border layer; positive inside.
// Throws Error naming the view if a mask is empty.
ScalarGrid visual_hull_field(const ViewSet& views, int resolution, HullMasks masks = HullMasks::Rgb);

// Throws Error if a mask is empty or the four masks share no volume.
Mesh carve_visual_hull(const ViewSet& views, const VisualHullOptions& options = {});

}  // namespace u3d
