#pragma once
// A closed mesh's signed distance sampled on a regular grid: positive inside, exact (to the nearest
// triangle, triangle_bvh.h) within a band around the surface and clamped to +-band beyond it, so a
// grid surface of it (marching_tetrahedra.h) passes where the mesh's surface is, within the grid's
// linear interpolation. Inside and outside come from the parity of the surface crossings along each
// grid column parallel to z, so the mesh must be closed; where it intersects itself, the parity
// decides.
#include "core/mesh.h"
#include "geometry/marching_tetrahedra.h"

namespace u3d {

// Fills grid.values (grid.nx * grid.ny * grid.nz samples at grid.position) with the signed distance of
// `mesh` in world units, clamped to +-band. Throws Error if the mesh has no faces or band <= 0.
void sample_signed_distance(const Mesh& mesh, float band, ScalarGrid& grid);

}  // namespace u3d
