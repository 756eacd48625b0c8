#include "geometry/icosphere.h"

#include <cmath>
#include <map>
#include <utility>

#include "core/error.h"

namespace u3d {

Mesh make_icosphere(int subdivisions, float radius) {
  require(subdivisions >= 0 && subdivisions <= 8, "icosphere subdivisions must be in [0, 8]");
  require(radius > 0.f, "icosphere radius must be positive");
  const float t = (1.f + std::sqrt(5.f)) / 2.f;
  Mesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3f& p : m.positions) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto [it, inserted] = midpoint.try_emplace(key, int(m.positions.size()));
      if (inserted) m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      return it->second;
    };
    std::vector<Vec3i> faces;
    faces.reserve(m.faces.size() * 4);
    for (const Vec3i& f : m.faces) {
      const int a = mid(f[0], f[1]), b = mid(f[1], f[2]), c = mid(f[2], f[0]);
      faces.push_back({f[0], a, c});
      faces.push_back({f[1], b, a});
      faces.push_back({f[2], c, b});
      faces.push_back({a, b, c});
    }
    m.faces = std::move(faces);
  }
  for (Vec3f& p : m.positions) p *= radius;
  return m;
}

}  // namespace u3d
