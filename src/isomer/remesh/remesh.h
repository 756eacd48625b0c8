#pragma once
// One remeshing pass of continuous remeshing, run after every optimizer step: collapse short edges
// and bad faces, split long edges, drop unreferenced vertices, then flip edges toward valence 6.
#include <cstddef>
#include <random>
#include <vector>

#include "core/mesh.h"
#include "geometry/edge_topology.h"
#include "isomer/remesh/vertex_rows.h"

namespace u3d {

struct RemeshCounts {
  int collapses = 0;
  int splits = 0;
  int flips = 0;
};

// min/max_edge_length are per vertex (consumed). Rows of removed vertices disappear and rows keep
// following their vertices. No splits once the mesh has max_vertices vertices. `cache`, if given, holds
// the topology of `faces` between passes (the caller must not edit the faces in between).
RemeshCounts remesh_pass(VertexRows& rows, std::vector<Vec3i>& faces, std::vector<float> min_edge_length,
                         std::vector<float> max_edge_length, bool flip, std::mt19937& rng,
                         size_t max_vertices = 1000000, TopologyCache* cache = nullptr);

// Removes vertices no face references, renumbering faces; returns the old index of each kept vertex.
std::vector<int> drop_unreferenced_vertices(VertexRows& rows, std::vector<Vec3i>& faces);

}  // namespace u3d
