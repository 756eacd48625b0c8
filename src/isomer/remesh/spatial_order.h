#pragma once
// Renumbers a mesh's vertices and faces in space-filling-curve order. Remeshing appends new vertices
// and faces at the end and moves others into freed slots, so after a few passes neighbours on the
// surface sit far apart in memory; every per-pixel pass (rasterizing, interpolating, the per-face
// gradient sums) then misses the cache on nearly every face it meets. Z-order keeps them close.
#include <vector>

#include "core/mesh.h"
#include "isomer/remesh/vertex_rows.h"

namespace u3d {

// Vertices sorted by the Morton code of their position (within the mesh's bounding box), rows moved
// with them; faces renumbered (winding kept) and sorted by their lowest new vertex index. Stable, so
// the result depends only on the input.
void reorder_spatially(VertexRows& rows, std::vector<Vec3i>& faces);

}  // namespace u3d
