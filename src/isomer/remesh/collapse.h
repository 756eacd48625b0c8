#pragma once
// Edge collapse of continuous remeshing (Palfinger 2022): edges much shorter than the local minimum
// length, and one edge of every face that is tiny or flipped against its vertex normals, are collapsed
// to their midpoint. Collapses are chosen greedily by priority with disjoint one-rings, and only where
// the link condition holds, so the mesh stays a manifold with consistent orientation.
#include <random>
#include <vector>

#include "core/mesh.h"
#include "geometry/edge_topology.h"
#include "isomer/remesh/vertex_rows.h"

namespace u3d {

struct CollapseOptions {
  float area_ratio = 0.5f;            // a face is tiny below area_ratio * min_edge_length^2
  float shortest_probability = 0.8f;  // a flagged face gives up its shortest edge with this probability
};

// Collapses edges in place: the kept vertex's row becomes the mean of both rows, the removed vertex is
// left unreferenced, and the two faces of each collapsed edge are deleted. `topology` is that of `faces`
// on entry (stale afterwards when anything collapsed). Returns the collapse count.
int collapse_short_edges(VertexRows& rows, std::vector<Vec3i>& faces, const EdgeTopology& topology,
                         const std::vector<float>& min_edge_length, std::mt19937& rng,
                         const CollapseOptions& options = {});

}  // namespace u3d
