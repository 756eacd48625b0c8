#pragma once
// Topology checks of a reconstructed surface: ISOMER promises a closed, manifold mesh.
#include <string>

#include "core/mesh.h"

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

}  // namespace u3d
