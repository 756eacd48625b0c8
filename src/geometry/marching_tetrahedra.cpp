#include "geometry/marching_tetrahedra.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <unordered_map>

#include "core/error.h"

namespace u3d {
namespace {

// A cube corner as three bits (x = 1, y = 2, z = 4) of its offset from the cube's base sample.
using Corner = int;
Vec3f corner_offset(Corner c) { return Vec3f(float(c & 1), float((c >> 1) & 1), float((c >> 2) & 1)); }

// A grid edge cut by the surface, as its two cube corners; `low`'s bits are a subset of `high`'s
// (every Kuhn edge steps forward), so (low sample, high - low) names the edge uniquely in the grid.
struct CutEdge {
  Corner low = 0, high = 0;
};
using Triangle = std::array<CutEdge, 3>;

struct TetCase {
  int count = 0;
  std::array<Triangle, 2> triangles;
};

// The six Kuhn tetrahedra: monotone paths from corner 0 to corner 7, one per order of the axes.
std::array<std::array<Corner, 4>, 6> kuhn_tetrahedra() {
  std::array<std::array<Corner, 4>, 6> tets;
  std::array<int, 3> axes = {0, 1, 2};
  int t = 0;
  do {
    const Corner c1 = 1 << axes[0], c2 = c1 | (1 << axes[1]);
    tets[t++] = {0, c1, c2, 7};
  } while (std::next_permutation(axes.begin(), axes.end()));
  return tets;
}

// The triangles of every (tetrahedron, inside-vertex set), oriented once here with exact corner
// coordinates: the orientation at the edge midpoints is the orientation for every cut position,
// because the cut is a planar convex polygon separating inside from outside vertices for all of them.
struct CaseTable {
  std::array<std::array<Corner, 4>, 6> tets = kuhn_tetrahedra();
  std::array<std::array<TetCase, 16>, 6> cases;

  CaseTable() {
    for (int t = 0; t < 6; ++t)
      for (int mask = 0; mask < 16; ++mask) cases[t][mask] = build(tets[t], mask);
  }

  static CutEdge edge(Corner a, Corner b) { return (a & b) == a ? CutEdge{a, b} : CutEdge{b, a}; }

  static TetCase build(const std::array<Corner, 4>& tet, int mask) {
    std::vector<Corner> in, out;
    for (int k = 0; k < 4; ++k) (mask >> k & 1 ? in : out).push_back(tet[k]);
    TetCase result;
    if (in.size() == 1 || in.size() == 3) {
      const std::vector<Corner>& lone = in.size() == 1 ? in : out;
      const std::vector<Corner>& rest = in.size() == 1 ? out : in;
      result.triangles[result.count++] = {edge(lone[0], rest[0]), edge(lone[0], rest[1]), edge(lone[0], rest[2])};
    } else if (in.size() == 2) {
      // Quad around the cut: (in0,out0) (in0,out1) (in1,out1) (in1,out0), split along one diagonal.
      const CutEdge q0 = edge(in[0], out[0]), q1 = edge(in[0], out[1]), q2 = edge(in[1], out[1]), q3 = edge(in[1], out[0]);
      result.triangles[result.count++] = {q0, q1, q2};
      result.triangles[result.count++] = {q0, q2, q3};
    }
    Vec3f inward = Vec3f::Zero();  // from the outside vertices' mean to the inside vertices' mean
    for (Corner c : in) inward += corner_offset(c) / float(in.size());
    for (Corner c : out) inward -= corner_offset(c) / float(out.size());
    for (int i = 0; i < result.count; ++i) {
      Triangle& tri = result.triangles[i];
      auto mid = [](const CutEdge& e) -> Vec3f { return 0.5f * (corner_offset(e.low) + corner_offset(e.high)); };
      const Vec3f normal = (mid(tri[1]) - mid(tri[0])).cross(mid(tri[2]) - mid(tri[0]));
      if (normal.dot(inward) > 0.f) std::swap(tri[1], tri[2]);  // outward normals
    }
    return result;
  }
};

// Keeps cut points off the samples themselves, so vertices of different edges never coincide.
constexpr float kMinEdgeFraction = 1e-3f;

}  // namespace

Mesh extract_zero_surface(const ScalarGrid& grid) {
  require(grid.nx >= 2 && grid.ny >= 2 && grid.nz >= 2, "iso-surface: the grid needs at least 2 samples per axis");
  require(grid.values.size() == size_t(grid.nx) * size_t(grid.ny) * size_t(grid.nz),
          "iso-surface: the grid's value count does not match its size");
  for (int z = 0; z < grid.nz; ++z)
    for (int y = 0; y < grid.ny; ++y)
      for (int x = 0; x < grid.nx; ++x) {
        const bool border = x == 0 || y == 0 || z == 0 || x == grid.nx - 1 || y == grid.ny - 1 || z == grid.nz - 1;
        require(!border || !(grid.values[grid.index(x, y, z)] > 0.f), "iso-surface: a grid border sample is inside");
      }

  static const CaseTable table;
  std::array<size_t, 8> corner_step;
  for (Corner c = 0; c < 8; ++c) corner_step[c] = grid.index(c & 1, (c >> 1) & 1, (c >> 2) & 1);

  Mesh mesh;
  std::unordered_map<uint64_t, int> vertex_of_edge;
  auto vertex = [&](size_t base, int x, int y, int z, const CutEdge& e) {
    const size_t a = base + corner_step[e.low], b = base + corner_step[e.high];
    const uint64_t key = uint64_t(a) * 8 + uint64_t(e.high & ~e.low);
    auto [it, added] = vertex_of_edge.try_emplace(key, int(mesh.positions.size()));
    if (added) {
      const float va = grid.values[a], vb = grid.values[b];
      const float t = std::clamp(va / (va - vb), kMinEdgeFraction, 1.f - kMinEdgeFraction);
      const Vec3f pa = grid.position(x, y, z) + grid.spacing * corner_offset(e.low);
      const Vec3f pb = grid.position(x, y, z) + grid.spacing * corner_offset(e.high);
      mesh.positions.push_back(pa + t * (pb - pa));
    }
    return it->second;
  };

  for (int z = 0; z + 1 < grid.nz; ++z)
    for (int y = 0; y + 1 < grid.ny; ++y)
      for (int x = 0; x + 1 < grid.nx; ++x) {
        const size_t base = grid.index(x, y, z);
        int inside = 0;  // bit c: corner c is inside
        for (Corner c = 0; c < 8; ++c) inside |= (grid.values[base + corner_step[c]] > 0.f) << c;
        if (inside == 0 || inside == 0xff) continue;
        for (int t = 0; t < 6; ++t) {
          int mask = 0;
          for (int k = 0; k < 4; ++k) mask |= (inside >> table.tets[t][k] & 1) << k;
          const TetCase& tc = table.cases[t][mask];
          for (int i = 0; i < tc.count; ++i) {
            Vec3i face;
            for (int k = 0; k < 3; ++k) face[k] = vertex(base, x, y, z, tc.triangles[i][k]);
            mesh.faces.push_back(face);
          }
        }
      }
  return mesh;
}

}  // namespace u3d
