#pragma once
// Icosphere (subdivided icosahedron): the sphere initialisation of the coarse stage ("ball" init of the
// official code) and a well-shaped closed test mesh.
#include "core/mesh.h"

namespace u3d {

// Closed, CCW-outward sphere mesh: 20 * 4^subdivisions faces.
Mesh make_icosphere(int subdivisions, float radius);

}  // namespace u3d
