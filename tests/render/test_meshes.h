#pragma once
// Small meshes built in code for the render tests.
#include "core/mesh.h"

namespace u3d::test {

// Appends an axis-aligned box with 4 vertices per side (so vertex normals equal face normals) and
// faces counter-clockwise seen from outside.
inline void add_box(Mesh& mesh, const Vec3f& lo, const Vec3f& hi) {
  for (int axis = 0; axis < 3; ++axis)
    for (int sign : {-1, 1}) {
      int u = (axis + 1) % 3, v = (axis + 2) % 3;  // (u, v, axis) is right-handed
      Vec3f corner[4];
      const float uu[4] = {lo[u], hi[u], hi[u], lo[u]}, vv[4] = {lo[v], lo[v], hi[v], hi[v]};
      for (int k = 0; k < 4; ++k) {
        corner[k][axis] = sign > 0 ? hi[axis] : lo[axis];
        corner[k][u] = uu[k];
        corner[k][v] = vv[k];
      }
      int b = int(mesh.positions.size());
      for (const auto& c : corner) mesh.positions.push_back(c);
      if (sign > 0) {
        mesh.faces.push_back({b, b + 1, b + 2});
        mesh.faces.push_back({b, b + 2, b + 3});
      } else {
        mesh.faces.push_back({b, b + 2, b + 1});
        mesh.faces.push_back({b, b + 3, b + 2});
      }
    }
}

// A unit cube [-0.5, 0.5]^3 with three different bumps, so every view is distinguishable:
// a thin one on +X (x up to 0.85), a thin one on +Z (z up to 0.75) and a wide flat one on +Y (y up to 0.7).
inline Mesh bumpy_cube() {
  Mesh m;
  add_box(m, {-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f});
  add_box(m, {0.5f, -0.1f, -0.1f}, {0.85f, 0.1f, 0.1f});
  add_box(m, {-0.1f, -0.1f, 0.5f}, {0.1f, 0.1f, 0.75f});
  add_box(m, {-0.3f, 0.5f, -0.3f}, {0.3f, 0.7f, 0.3f});
  return m;
}

}  // namespace u3d::test
