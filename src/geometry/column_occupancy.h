#pragma once
// Inside and outside of a closed triangle mesh on a regular grid, by counting the mesh's signed
// crossings along the grid's z columns (exact for closed meshes, and fast: each triangle is visited
// once, for the columns its xy projection covers).
//
// Winding. For a sample p, w(p) = sum over the crossings of the column above p (larger z) of +1 where
// the crossing face's normal points to +z and -1 where it points to -z. For a closed mesh this is its
// winding number at p: 1 inside and 0 outside an outward mesh. A sample counts as inside when w != 0,
// so where a self-intersecting surface turns inside out (the front and back sheets of a thin plate
// that crossed: w = -1 between them) the region between the sheets is solid as well.
//
// Column hits use the top-left rule of rasterisers on an edge function that is exactly antisymmetric
// between the two faces sharing an edge, so a column through an edge or a vertex is counted once.
//
// Field. The value at a sample is +-0.5 * min(1, d / spacing), positive inside, with d the distance
// along the column to the nearest crossing: the zero level set (marching_tetrahedra.h) then passes
// through the crossings along z.
#include <vector>

#include "core/mesh.h"
#include "geometry/marching_tetrahedra.h"

namespace u3d {

// A field on `layout`'s samples (its values are replaced), from the faces of a closed mesh. Throws
// Error if a column's crossings do not sum to zero (the mesh is open where the column passes).
ScalarGrid column_occupancy_field(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                                  ScalarGrid layout);

}  // namespace u3d
