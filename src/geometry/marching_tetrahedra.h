#pragma once
// Iso-surface extraction from a scalar field sampled on a regular grid: the zero level set of the
// field's piecewise-linear interpolation over the Kuhn triangulation of the grid (every cube split
// into six tetrahedra along its main diagonal; neighbouring cubes split their shared faces along the
// same diagonal). Unlike marching cubes this has no ambiguous cases and needs no 256-entry table:
// each tetrahedron is cut by at most one plane piece, so the surface is a closed, edge- and
// vertex-manifold triangle mesh whenever the field is negative on the whole grid border.
//
// Inside is where the field is positive; faces wind counter-clockwise seen from outside (outward
// normals). A sample exactly 0 counts as outside.
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct ScalarGrid {
  int nx = 0, ny = 0, nz = 0;  // samples per axis
  Vec3f origin{0, 0, 0};       // world position of sample (0, 0, 0)
  float spacing = 1.f;         // world distance between neighbouring samples
  std::vector<float> values;   // x fastest: index = x + nx * (y + ny * z)

  size_t index(int x, int y, int z) const { return size_t(x) + size_t(nx) * (size_t(y) + size_t(ny) * size_t(z)); }
  Vec3f position(int x, int y, int z) const { return origin + spacing * Vec3f(float(x), float(y), float(z)); }
};

// Throws Error if the grid is malformed or a border sample is positive (the surface would be open).
// Returns an empty mesh when no sample is positive.
Mesh extract_zero_surface(const ScalarGrid& grid);

}  // namespace u3d
