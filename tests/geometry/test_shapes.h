#pragma once
// Small analytic meshes with known areas, volumes and distances for the metric tests.
#include <cmath>
#include <map>
#include <utility>

#include "core/mesh.h"

namespace u3d::test {

// Axis-aligned box, outward counter-clockwise faces, 8 shared vertices.
inline Mesh box_mesh(const Vec3f& lo, const Vec3f& hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    m.faces.emplace_back(q[0], q[1], q[2]);
    m.faces.emplace_back(q[0], q[2], q[3]);
  }
  return m;
}

// Icosphere: an icosahedron subdivided `levels` times, vertices projected onto the sphere.
inline Mesh sphere_mesh(float radius, int levels, const Vec3f& centre = Vec3f::Zero()) {
  const float t = (1.f + std::sqrt(5.f)) / 2.f;
  Mesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : m.positions) p.normalize();
  m.faces = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
             {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      return midpoint[key] = int(m.positions.size()) - 1;
    };
    std::vector<Vec3i> next;
    for (const auto& f : m.faces) {
      int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.insert(next.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    m.faces = std::move(next);
  }
  for (auto& p : m.positions) p = centre + radius * p;
  return m;
}

inline Mesh flipped(Mesh m) {
  for (auto& f : m.faces) std::swap(f[1], f[2]);
  return m;
}

}  // namespace u3d::test
