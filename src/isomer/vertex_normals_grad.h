#pragma once
// Differentiable area-weighted vertex normals (the official calc_vertex_normals: the normalised sum of
// the un-normalised face normals around each vertex), so losses on rendered normals reach positions.
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct VertexNormals {
  std::vector<Vec3f> unit;  // per vertex, normalised (zero where the sum vanishes)
  std::vector<float> norm;  // per vertex length of the un-normalised sum
};

VertexNormals compute_vertex_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces);

// Adds dL/d(positions) given dL/d(unit normals).
void vertex_normals_backward(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                             const VertexNormals& normals, const std::vector<Vec3f>& grad_unit,
                             std::vector<Vec3f>& grad_positions);

}  // namespace u3d
