#pragma once
// Edge split of continuous remeshing: every edge longer than the local maximum length gets a midpoint
// vertex (mean row of its ends), and each face is re-triangulated by how many of its sides were split.
// Both faces of an edge use the same midpoint, so the result stays conforming and manifold.
#include <vector>

#include "core/mesh.h"
#include "geometry/edge_topology.h"
#include "isomer/remesh/vertex_rows.h"

namespace u3d {

// Splits in place; max_edge_length is per vertex and grows with the new vertices (mean of the ends).
// `topology` is that of `faces` on entry (stale afterwards when anything split). Returns the number of
// split edges.
int split_long_edges(VertexRows& rows, std::vector<Vec3i>& faces, const EdgeTopology& topology,
                     std::vector<float>& max_edge_length);

}  // namespace u3d
