#pragma once
// Topology checks of a reconstructed surface: ISOMER promises a closed, manifold mesh.
#include <string>
#include <vector>

#include "core/mesh.h"
#include "geometry/edge_topology.h"

namespace u3d {

struct MeshTopology {
  bool edge_manifold = false;    // every edge has at most two faces, wound in opposite directions
  bool vertex_manifold = false;  // every vertex's faces form one fan
  bool watertight = false;       // every edge has exactly two faces: closed (self-intersection not tested)
  int components = 0;            // connected pieces (by shared edges)
  int euler_characteristic = 0;  // V - E + F (2 per closed genus-0 piece)
  double volume = 0.0;           // signed enclosed volume; positive when faces wind outward

  bool closed_manifold() const { return edge_manifold && vertex_manifold && watertight; }
  std::string summary() const;
};

MeshTopology mesh_topology(const Mesh& mesh);

// The same for the surface a textured mesh describes: vertices at identical positions (the copies a
// UV seam makes) count as one.
MeshTopology surface_topology(const Mesh& mesh);

// Per vertex, how many fans its faces form (0 when no face uses it): two faces at a vertex are in one
// fan when a chain of faces joins them, each traversing an edge at the vertex opposite to the next.
std::vector<int> vertex_fan_counts(const std::vector<Vec3i>& faces, const EdgeTopology& topology,
                                   size_t vertex_count);

}  // namespace u3d
