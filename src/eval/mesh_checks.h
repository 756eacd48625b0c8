#pragma once
// Diagnostics that decide which warnings an evaluation prints: a reconstruction with holes or
// degenerate faces still gets metrics, but the user should know the volume is approximate.
#include <string>
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct MeshDiagnostics {
  size_t boundary_edges = 0;     // edges used by exactly one face (holes, open borders)
  size_t nonmanifold_edges = 0;  // edges used by three or more faces
  size_t degenerate_faces = 0;   // zero area or repeated vertex
  bool closed() const { return boundary_edges == 0; }
};

MeshDiagnostics diagnose_mesh(const Mesh& mesh);

// Human-readable warnings about `mesh` (named `what`), empty when it is a clean closed surface.
std::vector<std::string> mesh_warnings(const MeshDiagnostics& d, const std::string& what);

}  // namespace u3d
