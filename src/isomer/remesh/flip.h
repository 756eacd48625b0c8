#pragma once
// Edge flip of continuous remeshing: an interior edge is flipped when that brings the valences of its
// four vertices closer to 6 and both new faces keep the orientation of the old pair. Flips are chosen
// greedily by gain with disjoint vertex sets.
#include <vector>

#include "core/mesh.h"
#include "geometry/edge_topology.h"
#include "isomer/remesh/vertex_rows.h"

namespace u3d {

// Flips in place and patches `topology` (that of `faces` on entry) to match the flipped faces, so it
// stays valid for the next pass. Returns the number of flipped edges.
int flip_edges_for_valence(const VertexRows& rows, std::vector<Vec3i>& faces, EdgeTopology& topology);

}  // namespace u3d
