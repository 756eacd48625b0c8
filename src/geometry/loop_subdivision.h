#pragma once
// One step of Loop subdivision (Loop 1987): every triangle becomes four, each edge gets a vertex at
// 3/8 of its ends plus 1/8 of the two opposite corners, and each old vertex moves toward its ring with
// Warren's weight (3/16 at valence 3, 3/(8n) otherwise), the rule Open3D's SubdivideLoop uses too. Edges with other than two faces use the
// midpoint and their vertices stay put, so a surface with a border or a crumb never breaks the step.
// Linear time on the EdgeTopology arrays; Open3D's SubdivideLoop spent seconds in hash maps here.
#include "core/mesh.h"

namespace u3d {

// positions and faces only: the other attributes of `mesh` are not carried over.
Mesh loop_subdivide(const Mesh& mesh);

}  // namespace u3d
