#pragma once
// Connected pieces of the inside of a sampled field: how many separate solids a grid holds (the
// visual hull of a set of masks, a carved field) before any surface is extracted.
#include "geometry/marching_tetrahedra.h"

namespace u3d {

// The number of 6-connected groups of positive samples (inside, as extract_zero_surface reads them).
int count_inside_components(const ScalarGrid& grid);

}  // namespace u3d
