#pragma once
// The visual hull of the four views: the largest shape whose silhouettes fit inside all four masks,
// a baseline that uses the masks only (no normals). docs/evaluation.md compares it with ISOMER.
//
// Carving. A grid of resolution^3 voxels spans the views' orthographic box [-1, 1]^3. At each voxel
// centre the field is
//     min over the four views of (alpha at the centre's projection - 0.5),
// alpha read bilinearly from the view's RGB alpha channel with its own camera (view_camera), so the
// centre is kept exactly when it projects inside every mask (alpha > 0.5) and the field also says
// how far inside, to sub-voxel precision. One layer of outside samples surrounds the grid, so an
// object touching the box still gives a closed surface.
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
