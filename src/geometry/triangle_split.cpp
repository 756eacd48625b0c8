#include "geometry/triangle_split.h"

#include <algorithm>
#include <array>

#include "core/error.h"

namespace u3d {

TriangleSoup split_long_triangles(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, float max_edge) {
  require(max_edge > 0, "split_long_triangles: max_edge must be positive");
  TriangleSoup out;
  out.positions = positions;
  out.faces.reserve(faces.size());
  const float max2 = max_edge * max_edge;
  std::vector<std::array<Vec3f, 3>> pending;
  for (const auto& f : faces) {
    const Vec3f &a = positions[f[0]], &b = positions[f[1]], &c = positions[f[2]];
    if (std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}) <= max2) {
      out.faces.push_back(f);  // short enough: keep it with its shared vertices
      continue;
    }
    pending.push_back({a, b, c});
    while (!pending.empty()) {
      std::array<Vec3f, 3> t = pending.back();
      pending.pop_back();
      // Rotate so the longest edge is t[0] -> t[1] (keeps the winding order).
      float e0 = (t[1] - t[0]).squaredNorm(), e1 = (t[2] - t[1]).squaredNorm(), e2 = (t[0] - t[2]).squaredNorm();
      if (e1 >= e0 && e1 >= e2) t = {t[1], t[2], t[0]};
      else if (e2 >= e0 && e2 >= e1) t = {t[2], t[0], t[1]};
      if ((t[1] - t[0]).squaredNorm() <= max2) {
        int base = int(out.positions.size());
        out.positions.insert(out.positions.end(), t.begin(), t.end());
        out.faces.emplace_back(base, base + 1, base + 2);
        continue;
      }
      Vec3f m = 0.5f * (t[0] + t[1]);
      pending.push_back({t[0], m, t[2]});
      pending.push_back({m, t[1], t[2]});
    }
  }
  return out;
}

}  // namespace u3d
