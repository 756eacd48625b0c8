#pragma once
// Splitting long triangles so a bounding-volume hierarchy stays tight. Meshes with long sliver
// triangles (surfaces of revolution, caps made of fans) give every cluster a radius close to the
// object size; a hierarchical winding number then sums nearly every triangle exactly for every query.
// Splitting a triangle into pieces that tile it changes no solid angle, only the cost.
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct TriangleSoup {
  std::vector<Vec3f> positions;
  std::vector<Vec3i> faces;
};

// Longest-edge bisection until no edge is longer than max_edge (> 0). Orientation is kept; the
// pieces do not share vertices across split edges (T-junctions are harmless for solid angles).
TriangleSoup split_long_triangles(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, float max_edge);

}  // namespace u3d
