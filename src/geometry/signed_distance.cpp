#include "geometry/signed_distance.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/error.h"
#include "geometry/triangle_bvh.h"

namespace u3d {
namespace {

using Point2 = std::pair<double, double>;

// Twice the signed area of (a, b, p) in the xy plane, from the edge's endpoints in a fixed order: the
// two triangles that share an edge get exactly opposite values, so a column through the edge crosses
// exactly one of them.
double edge_value(const Point2& a, const Point2& b, const Point2& p) {
  const bool swapped = b < a;
  const Point2& u = swapped ? b : a;
  const Point2& v = swapped ? a : b;
  const double value = (v.first - u.first) * (p.second - u.second) - (v.second - u.second) * (p.first - u.first);
  return swapped ? -value : value;
}

// Whether a column exactly on the edge a -> b of a counter-clockwise triangle belongs to it: true for
// one of the edge's two directions only (a top-left rule).
bool owns_edge(const Point2& a, const Point2& b) {
  const double dy = b.second - a.second;
  return dy < 0 || (dy == 0 && b.first > a.first);
}

}  // namespace

void sample_signed_distance(const Mesh& mesh, float band, ScalarGrid& grid) {
  require(band > 0.f, "signed distance: the band must be positive, got " + std::to_string(band));
  const TriangleBvh bvh(mesh.positions, mesh.faces);
  const int nx = grid.nx, ny = grid.ny, nz = grid.nz;
  const double h = grid.spacing;
  const Vec3f origin = grid.origin;
  auto lowest = [&](float value, int axis, int n) {
    return std::clamp(int(std::ceil((double(value) - origin[axis]) / h)), 0, n);
  };
  auto highest = [&](float value, int axis, int n) {
    return std::clamp(int(std::floor((double(value) - origin[axis]) / h)), -1, n - 1);
  };

  // The surface crossings of every z column, and the samples within `band` of a triangle's box.
  std::vector<std::pair<int, float>> crossings;  // (column x + nx * y, z)
  std::vector<uint8_t> near(size_t(nx) * ny * nz, 0);
  for (const Vec3i& f : mesh.faces) {
    Vec3f a = mesh.positions[size_t(f[0])], b = mesh.positions[size_t(f[1])], c = mesh.positions[size_t(f[2])];
    const Vec3f lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    for (int z = lowest(lo.z() - band, 2, nz); z <= highest(hi.z() + band, 2, nz); ++z)
      for (int y = lowest(lo.y() - band, 1, ny); y <= highest(hi.y() + band, 1, ny); ++y)
        for (int x = lowest(lo.x() - band, 0, nx); x <= highest(hi.x() + band, 0, nx); ++x)
          near[grid.index(x, y, z)] = 1;
    Point2 p0(a.x(), a.y()), p1(b.x(), b.y()), p2(c.x(), c.y());
    const double area = edge_value(p0, p1, p2);
    if (area == 0) continue;  // seen edge-on along z: the columns cross its neighbours
    // Counter-clockwise seen along z.
    if (area < 0) std::swap(p1, p2), std::swap(b, c);
    for (int y = lowest(lo.y(), 1, ny); y <= highest(hi.y(), 1, ny); ++y)
      for (int x = lowest(lo.x(), 0, nx); x <= highest(hi.x(), 0, nx); ++x) {
        const Point2 p(origin.x() + h * x, origin.y() + h * y);
        const double w0 = edge_value(p1, p2, p), w1 = edge_value(p2, p0, p), w2 = edge_value(p0, p1, p);
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        if ((w0 == 0 && !owns_edge(p1, p2)) || (w1 == 0 && !owns_edge(p2, p0)) || (w2 == 0 && !owns_edge(p0, p1)))
          continue;
        const double z = (w0 * a.z() + w1 * b.z() + w2 * c.z()) / (w0 + w1 + w2);
        crossings.emplace_back(x + nx * y, float(z));
      }
  }
  std::sort(crossings.begin(), crossings.end());

  // Inside where an odd number of crossings lies below the sample.
  grid.values.assign(near.size(), -band);
  std::vector<size_t> column_start(size_t(nx) * ny + 1, 0);
  for (const auto& crossing : crossings) ++column_start[size_t(crossing.first) + 1];
  for (size_t i = 1; i < column_start.size(); ++i) column_start[i] += column_start[i - 1];
#pragma omp parallel for schedule(dynamic)
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      const size_t column = size_t(x) + size_t(nx) * y;
      size_t next = column_start[column];
      const size_t end = column_start[column + 1];
      for (int z = 0; z < nz; ++z) {
        const float position = origin.z() + float(h) * float(z);
        while (next < end && crossings[next].second < position) ++next;
        if ((next - column_start[column]) % 2 == 1) grid.values[grid.index(x, y, z)] = band;
      }
    }

#pragma omp parallel for schedule(dynamic)
  for (int z = 0; z < nz; ++z)  // exact distances near the surface
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        const size_t i = grid.index(x, y, z);
        if (!near[i]) continue;
        const float distance = std::min(bvh.closest_point(grid.position(x, y, z)).distance, band);
        grid.values[i] = grid.values[i] > 0.f ? distance : -distance;
      }
}

}  // namespace u3d
