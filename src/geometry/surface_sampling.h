#pragma once
// Uniform random points on a triangle surface: the point sets behind Chamfer distance and F-score.
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct SurfaceSamples {
  std::vector<Vec3f> points;
  std::vector<int> faces;  // face each point lies on
};

// `count` points distributed uniformly by area over all faces (zero-area faces never get a point).
// Deterministic for a given seed. Throws Error when the mesh has no surface area.
SurfaceSamples sample_surface(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, size_t count,
                              uint64_t seed);

// Total area of the triangles.
double surface_area(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces);

}  // namespace u3d
