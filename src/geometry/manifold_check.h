#pragma once
// Structural validation of a closed, consistently oriented triangle 2-manifold (test and debug aid).
#include <string>
#include <vector>

#include "core/mesh.h"

namespace u3d {

// Empty when every edge has exactly two faces traversing it in opposite directions, every vertex is
// referenced and its faces form a single fan, and no face is degenerate; otherwise the first problem.
std::string closed_manifold_problem(const std::vector<Vec3i>& faces, size_t vertex_count);

}  // namespace u3d
