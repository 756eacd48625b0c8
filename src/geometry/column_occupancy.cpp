#include "geometry/column_occupancy.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace u3d {
namespace {

struct Crossing {
  float z;
  int sign;  // +1: the face's normal points to +z
};

// Edge function of the directed edge p -> q at x (twice the signed area of p, q, x), computed from the
// edge's lower-indexed end so that the two faces sharing an edge get exactly opposite values.
double edge_function(const std::vector<Eigen::Vector2d>& uv, int p, int q, const Eigen::Vector2d& x) {
  const int lo = std::min(p, q), hi = std::max(p, q);
  const Eigen::Vector2d e = uv[hi] - uv[lo], d = x - uv[lo];
  const double value = e.x() * d.y() - e.y() * d.x();
  return p == lo ? value : -value;
}

// Top-left rule: of the two opposite directions of an edge, exactly one owns the points on it.
bool owns_edge(const std::vector<Eigen::Vector2d>& uv, int p, int q) {
  const double dx = uv[q].x() - uv[p].x(), dy = uv[q].y() - uv[p].y();
  return dy < 0.0 || (dy == 0.0 && dx < 0.0);
}

}  // namespace

ScalarGrid column_occupancy_field(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                                  ScalarGrid grid) {
  require(grid.nx > 0 && grid.ny > 0 && grid.nz > 0 && grid.spacing > 0.f,
          "column occupancy: the grid needs samples on every axis and a positive spacing");
  grid.values.assign(size_t(grid.nx) * grid.ny * grid.nz, 0.f);
  // Vertex positions in column units: column (i, j) sits at (u, v) = (i, j).
  std::vector<Eigen::Vector2d> uv(positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    uv[i] = Eigen::Vector2d((double(positions[i].x()) - grid.origin.x()) / grid.spacing,
                            (double(positions[i].y()) - grid.origin.y()) / grid.spacing);

  std::vector<std::vector<Crossing>> columns(size_t(grid.nx) * grid.ny);
  for (const Vec3i& f : faces) {
    int a = f[0], b = f[1], c = f[2];
    const double area = edge_function(uv, a, b, uv[c]);
    if (area == 0.0) continue;  // seen edge-on: the column passes along it, not through it
    const int sign = area > 0.0 ? 1 : -1;
    if (area < 0.0) std::swap(b, c);  // counter-clockwise in (u, v) from here on
    const double twice_area = std::abs(area);
    const double u_lo = std::min({uv[a].x(), uv[b].x(), uv[c].x()}), u_hi = std::max({uv[a].x(), uv[b].x(), uv[c].x()});
    const double v_lo = std::min({uv[a].y(), uv[b].y(), uv[c].y()}), v_hi = std::max({uv[a].y(), uv[b].y(), uv[c].y()});
    const int i0 = std::max(0, int(std::ceil(u_lo))), i1 = std::min(grid.nx - 1, int(std::floor(u_hi)));
    const int j0 = std::max(0, int(std::ceil(v_lo))), j1 = std::min(grid.ny - 1, int(std::floor(v_hi)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Eigen::Vector2d x(i, j);
        const double wa = edge_function(uv, b, c, x), wb = edge_function(uv, c, a, x), wc = edge_function(uv, a, b, x);
        const bool inside = (wa > 0.0 || (wa == 0.0 && owns_edge(uv, b, c))) &&
                            (wb > 0.0 || (wb == 0.0 && owns_edge(uv, c, a))) &&
                            (wc > 0.0 || (wc == 0.0 && owns_edge(uv, a, b)));
        if (!inside) continue;
        const double z = (wa * positions[a].z() + wb * positions[b].z() + wc * positions[c].z()) / twice_area;
        columns[size_t(j) * grid.nx + i].push_back({float(z), sign});
      }
  }

  bool open = false;
#pragma omp parallel for schedule(dynamic, 64) reduction(|| : open)
  for (size_t col = 0; col < columns.size(); ++col) {
    std::vector<Crossing>& hits = columns[col];
    std::sort(hits.begin(), hits.end(), [](const Crossing& l, const Crossing& r) { return l.z < r.z; });
    int total = 0;
    for (const Crossing& h : hits) total += h.sign;
    if (total != 0) open = true;
    const int x = int(col % size_t(grid.nx)), y = int(col / size_t(grid.nx));
    size_t next = 0;
    int below = 0;
    for (int z = 0; z < grid.nz; ++z) {
      const float zs = grid.origin.z() + grid.spacing * float(z);
      while (next < hits.size() && hits[next].z <= zs) below += hits[next++].sign;
      float d = std::numeric_limits<float>::infinity();
      if (next > 0) d = zs - hits[next - 1].z;
      if (next < hits.size()) d = std::min(d, hits[next].z - zs);
      const float magnitude = 0.5f * std::min(1.f, d / grid.spacing);
      grid.values[grid.index(x, y, z)] = total - below != 0 ? magnitude : -magnitude;
    }
  }
  require(!open, "column occupancy: the mesh is not closed (a column crosses it an unbalanced number of times)");
  return grid;
}

}  // namespace u3d
