#pragma once
// Connected pieces of the inside of a sampled field: how many separate solids a grid holds (the
// visual hull of a set of masks, a carved field) before any surface is extracted.
#include "geometry/marching_tetrahedra.h"

namespace u3d {

// The number of 6-connected groups of positive samples (inside, as extract_zero_surface reads them).
int count_inside_components(const ScalarGrid& grid);

// Each sample's group (numbered from 0 in the order of their first samples; -1 outside); `count`, when
// given, receives the number of groups.
std::vector<int> label_inside_components(const ScalarGrid& grid, int* count = nullptr);

}  // namespace u3d
