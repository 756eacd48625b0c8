#include "geometry/uv_atlas.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>

#include "core/error.h"
#include "geometry/disjoint_sets.h"
#include "geometry/edge_topology.h"

namespace u3d {
namespace {

// The six chart axes and, for each, the plane basis (right, up) of an orthographic camera looking
// at the mesh from that side, so a face facing the axis stays counter-clockwise in (right, up).
struct Axis {
  Vec3f dir, right, up;
};
const std::array<Axis, 6> kAxes = {{
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},    // front
    {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},   // right
    {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},  // back
    {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},   // left
    {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},   // top
    {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},   // bottom
}};

struct Chart {
  int axis = 0;
  std::vector<int> faces;
  Vec2f turn{1, 0};             // (cos, sin) of the in-plane turn that gives the smallest bounding rectangle
  Vec2f min{0, 0}, size{0, 0};  // that rectangle, world units
  float area = 0.f;             // projected area, world units squared
  float stretch = 1.f;          // sqrt(surface area / projected area): the chart's share of the packing scale
  bool flat = false;            // known not to overlap itself (a piece of a chart that does not)
  int quarter_turns = 0;        // packed turned this many quarters counter-clockwise
  int x = 0, y = 0;             // packed position of its footprint's corner, packing cells
};

Vec2f project_axis(const Vec3f& p, int axis) { return Vec2f(p.dot(kAxes[axis].right), p.dot(kAxes[axis].up)); }

Vec2f project(const Vec3f& p, const Chart& c) {
  const Vec2f q = project_axis(p, c.axis);
  return Vec2f(c.turn.x() * q.x() - c.turn.y() * q.y(), c.turn.y() * q.x() + c.turn.x() * q.y());
}

float cross(const Vec2f& o, const Vec2f& a, const Vec2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Face-to-face adjacency across manifold interior edges: three neighbours per face, -1 on borders.
std::vector<std::array<int, 3>> face_neighbours(const Mesh& mesh) {
  const EdgeTopology topo = build_edge_topology(mesh.faces, mesh.positions.size());
  std::vector<std::array<int, 3>> out(mesh.faces.size(), {-1, -1, -1});
  for (size_t e = 0; e < topo.edge_count(); ++e) {
    if (!topo.interior(int(e))) continue;
    const int a = topo.edge_sides[e][0], b = topo.edge_sides[e][1];
    out[a / 3][a % 3] = b / 3;
    out[b / 3][b % 3] = a / 3;
  }
  return out;
}

// Edge-connected pieces of `faces` (a subset, all with one label) as separate face lists.
std::vector<std::vector<int>> connected_pieces(const std::vector<int>& faces,
                                               const std::vector<std::array<int, 3>>& neighbours,
                                               std::vector<int>& scratch_slot) {
  for (size_t i = 0; i < faces.size(); ++i) scratch_slot[faces[i]] = int(i);
  DisjointSets sets(faces.size());
  for (size_t i = 0; i < faces.size(); ++i)
    for (int n : neighbours[faces[i]])
      if (n >= 0 && scratch_slot[n] >= 0) sets.unite(int(i), scratch_slot[n]);
  std::vector<int> piece_of_root(faces.size(), -1);
  std::vector<std::vector<int>> pieces;
  for (size_t i = 0; i < faces.size(); ++i) {
    int& piece = piece_of_root[sets.find(int(i))];
    if (piece < 0) piece = int(pieces.size()), pieces.emplace_back();
    pieces[piece].push_back(faces[i]);
  }
  for (int f : faces) scratch_slot[f] = -1;
  return pieces;
}

// Projected and surface area of a chart, and the in-plane turn whose bounding rectangle is the smallest:
// one of the convex hull's edges lies on the smallest rectangle's side (rotating calipers, tried edge by edge).
void measure(Chart& c, const Mesh& mesh) {
  std::vector<Vec2f> corners;
  corners.reserve(c.faces.size() * 3);
  c.area = 0.f;
  float surface = 0.f;
  for (int f : c.faces) {
    const Vec3i& t = mesh.faces[f];
    const Vec2f a = project_axis(mesh.positions[t[0]], c.axis), b = project_axis(mesh.positions[t[1]], c.axis),
                d = project_axis(mesh.positions[t[2]], c.axis);
    c.area += 0.5f * std::abs(cross(a, b, d));
    surface += 0.5f * (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).norm();
    corners.insert(corners.end(), {a, b, d});
  }
  c.stretch = c.area > 0.f ? std::sqrt(surface / c.area) : 1.f;
  std::sort(corners.begin(), corners.end(),
            [](const Vec2f& a, const Vec2f& b) { return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y(); });
  std::vector<Vec2f> hull(2 * corners.size());  // Andrew's monotone chain, counter-clockwise
  size_t k = 0;
  for (size_t i = 0; i < corners.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], corners[i]) <= 0.f) --k;
    hull[k++] = corners[i];
  }
  for (size_t i = corners.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], corners[i]) <= 0.f) --k;
    hull[k++] = corners[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  float best = INFINITY;
  c.turn = Vec2f(1, 0);
  for (size_t i = 0; i < hull.size(); ++i) {
    const Vec2f e = hull[(i + 1) % hull.size()] - hull[i];
    if (!(e.norm() > 0.f)) continue;
    const Vec2f turn = Vec2f(e.x(), -e.y()) / e.norm();  // turns e onto +x
    Vec2f lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
    for (const Vec2f& q : hull) {
      const Vec2f r(turn.x() * q.x() - turn.y() * q.y(), turn.y() * q.x() + turn.x() * q.y());
      lo = lo.cwiseMin(r), hi = hi.cwiseMax(r);
    }
    const float box = (hi - lo).prod();
    if (box < best) best = box, c.turn = turn;
  }
  Vec2f lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (int f : c.faces)
    for (int v : {mesh.faces[f][0], mesh.faces[f][1], mesh.faces[f][2]}) {
      const Vec2f q = project(mesh.positions[v], c);
      lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    }
  c.min = lo;
  c.size = hi - lo;
}

// True when two faces of the chart cover one texel centre at `scale` texels per unit (texel centres
// strictly inside a triangle only, so faces sharing an edge never both claim a centre on it).
bool self_overlaps(const Chart& c, const Mesh& mesh, float scale) {
  if (c.faces.size() < 2) return false;
  const int w = int(std::ceil(c.size.x() * scale)) + 1, h = int(std::ceil(c.size.y() * scale)) + 1;
  std::vector<uint8_t> covered(size_t(w) * h, 0);
  for (int f : c.faces) {
    const Vec3i& t = mesh.faces[f];
    std::array<Vec2f, 3> q;
    for (int k = 0; k < 3; ++k) q[k] = (project(mesh.positions[t[k]], c) - c.min) * scale;
    const float area = (q[1] - q[0]).x() * (q[2] - q[0]).y() - (q[1] - q[0]).y() * (q[2] - q[0]).x();
    if (!(std::abs(area) > 0.f)) continue;
    const float sign = area > 0 ? 1.f : -1.f;
    const int x0 = std::max(0, int(std::floor(std::min({q[0].x(), q[1].x(), q[2].x()})))),
              x1 = std::min(w - 1, int(std::ceil(std::max({q[0].x(), q[1].x(), q[2].x()})))),
              y0 = std::max(0, int(std::floor(std::min({q[0].y(), q[1].y(), q[2].y()})))),
              y1 = std::min(h - 1, int(std::ceil(std::max({q[0].y(), q[1].y(), q[2].y()}))));
    for (int y = y0; y <= y1; ++y) {
      // Only texels near the triangle's extent within the row's strip [y, y + 1] (its corners there and
      // where its edges cross the strip's sides), a texel more either side, take the exact test.
      float lo = INFINITY, hi = -INFINITY;
      for (int k = 0; k < 3; ++k) {
        const Vec2f& a = q[k];
        const Vec2f& b = q[(k + 1) % 3];
        if (a.y() >= float(y) && a.y() <= float(y + 1)) lo = std::min(lo, a.x()), hi = std::max(hi, a.x());
        for (const float side : {float(y), float(y + 1)})
          if ((a.y() - side) * (b.y() - side) < 0.f) {
            const float x = a.x() + (side - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
            lo = std::min(lo, x), hi = std::max(hi, x);
          }
      }
      if (!(lo <= hi)) continue;
      const int first = std::max(x0, int(std::floor(lo)) - 1), last = std::min(x1, int(std::ceil(hi)) + 1);
      for (int x = first; x <= last; ++x) {
        const Vec2f p(x + 0.5f, y + 0.5f);
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Vec2f& a = q[k];
          const Vec2f& b = q[(k + 1) % 3];
          inside = sign * ((b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x())) > 0.f;
        }
        if (!inside) continue;
        uint8_t& cell = covered[size_t(y) * w + x];
        if (cell) return true;
        cell = 1;
      }
    }
  }
  return false;
}

// The chart's cells per side at `scale` (cells per world unit): cell (x, y) spans [x, x + 1] x [y, y + 1]
// of its projection.
Eigen::Vector2i chart_cells(const Chart& c, float scale) {
  const float s = scale * c.stretch;
  return Eigen::Vector2i(int(std::floor(c.size.x() * s)) + 1, int(std::floor(c.size.y() * s)) + 1);
}

// A chart's footprint at some scale on the packing grid. The chart claims the cells its triangles touch
// (conservatively: every cell whose square a triangle may meet), each grown by the gutter: the chart's
// cell (x, y) claims the footprint's [x, x + gutter] x [y, y + gutter] and lies at its (x + gutter / 2,
// y + gutter / 2). So the cells two charts touch are `gutter` empty cells apart, and those at the
// atlas's border gutter / 2 or more from it.
struct Footprint {
  int width = 0, height = 0;
  std::vector<uint8_t> cells;  // row-major, row 0 at the bottom (v up)
};

Footprint footprint(const Chart& c, const Mesh& mesh, float scale, int gutter) {
  const float s = scale * c.stretch;
  const Eigen::Vector2i n = chart_cells(c, scale);
  Footprint touched{n.x(), n.y(), std::vector<uint8_t>(size_t(n.x()) * n.y(), 0)};
  for (int f : c.faces) {
    std::array<Vec2f, 3> q;
    for (int k = 0; k < 3; ++k) q[k] = (project(mesh.positions[mesh.faces[f][k]], c) - c.min) * s;
    const float sign = cross(q[0], q[1], q[2]) >= 0.f ? 1.f : -1.f;
    const int y0 = std::clamp(int(std::floor(std::min({q[0].y(), q[1].y(), q[2].y()}))), 0, n.y() - 1),
              y1 = std::clamp(int(std::floor(std::max({q[0].y(), q[1].y(), q[2].y()}))), 0, n.y() - 1);
    const float x_lo = std::min({q[0].x(), q[1].x(), q[2].x()}), x_hi = std::max({q[0].x(), q[1].x(), q[2].x()});
    for (int y = y0; y <= y1; ++y) {
      // Cells whose square meets every edge's inner half-plane (a superset of the cells the triangle
      // meets): per edge, a linear bound on the cell centre x + 0.5.
      float lo = std::floor(x_lo), hi = std::floor(x_hi);
      for (int k = 0; k < 3; ++k) {
        const Vec2f& a = q[k];
        const Vec2f e = q[(k + 1) % 3] - a;
        const float slope = -sign * e.y();  // inside(x) = slope * (x + 0.5) + offset >= 0
        const float offset = sign * (e.x() * (y + 0.5f - a.y()) + e.y() * a.x()) + 0.5f * (std::abs(e.x()) + std::abs(e.y()));
        if (slope > 0.f) lo = std::max(lo, std::floor(-offset / slope - 0.5f));
        else if (slope < 0.f) hi = std::min(hi, std::ceil(-offset / slope - 0.5f));
        else if (offset < 0.f) hi = lo - 1.f;
      }
      const int first = std::max(0, int(lo)), last = std::min(n.x() - 1, int(hi));
      if (first <= last) std::fill_n(touched.cells.begin() + long(size_t(y) * n.x() + first), last - first + 1, uint8_t(1));
    }
  }
  // Grown by the gutter, along rows and then along columns.
  const int w = n.x() + gutter, h = n.y() + gutter;
  std::vector<uint8_t> along(size_t(w) * n.y(), 0);
  for (int y = 0; y < n.y(); ++y)
    for (int x = 0; x < n.x(); ++x)
      if (touched.cells[size_t(y) * n.x() + x])
        std::fill_n(along.begin() + long(size_t(y) * w + x), gutter + 1, uint8_t(1));
  Footprint out{w, h, std::vector<uint8_t>(size_t(w) * h, 0)};
  for (int y = 0; y < n.y(); ++y)
    for (int x = 0; x < w; ++x)
      if (along[size_t(y) * w + x])
        for (int d = 0; d <= gutter; ++d) out.cells[size_t(y + d) * w + x] = 1;
  return out;
}

// A grid `width` cells wide and `height` high with its claimed cells kept as runs: per cell, the number
// of free cells from it rightward (positive) or minus the number of claimed ones (negative), so a
// search skips whole runs; and per row, its longest free run and where it starts.
struct Occupancy {
  int width, height;
  std::vector<int> run, longest, longest_at;
  Occupancy(int w, int h) : width(w), height(h), run(size_t(w) * h), longest(h, w), longest_at(h, 0) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) run[size_t(y) * w + x] = w - x;
  }
  void claim_row(int y, int x0, int length) {
    int* row = run.data() + size_t(y) * width;
    const int end = x0 + length, after = end < width && row[end] < 0 ? -row[end] : 0;
    for (int x = x0; x < end; ++x) row[x] = x - end - after;
    for (int x = x0 - 1; x >= 0; --x) {  // the runs to the left again, until they stay as they were
      const int now = row[x] > 0 ? (row[x + 1] > 0 ? row[x + 1] + 1 : 1) : (row[x + 1] < 0 ? row[x + 1] - 1 : -1);
      if (now == row[x]) break;
      row[x] = now;
    }
    if (x0 < longest_at[y] + longest[y] && longest_at[y] < end) {
      longest[y] = 0;
      for (int x = 0; x < width; x += std::abs(row[x]))
        if (row[x] > longest[y]) longest[y] = row[x], longest_at[y] = x;
    }
  }
};

// Each row of a footprint turned `quarter_turns` quarters counter-clockwise as runs (first cell,
// length). A quarter turn takes cell (x, y) of a w x h footprint to (h - 1 - y, x): its rows are the
// footprint's columns, read from the top down.
using RowRuns = std::vector<std::vector<std::pair<int, int>>>;
RowRuns turned_runs(const Footprint& fp, int quarter_turns) {
  const bool columns = quarter_turns % 2 == 1;
  const int lines = columns ? fp.width : fp.height, length = columns ? fp.height : fp.width;
  const bool reverse_lines = quarter_turns >= 2, reverse_along = quarter_turns == 1 || quarter_turns == 2;
  RowRuns rows(lines);
  for (int line = 0; line < lines; ++line) {
    const int source = reverse_lines ? lines - 1 - line : line;
    auto cell = [&](int i) {
      return columns ? fp.cells[size_t(i) * fp.width + source] : fp.cells[size_t(source) * fp.width + i];
    };
    std::vector<std::pair<int, int>>& out = rows[line];
    for (int i = 0; i < length;) {
      if (!cell(i)) {
        ++i;
        continue;
      }
      int end = i;
      while (end < length && cell(end)) ++end;
      out.emplace_back(reverse_along ? length - end : i, end - i);
      i = end;
    }
    if (reverse_along) std::reverse(out.begin(), out.end());
  }
  return rows;
}

// The lowest, then leftmost, position where the footprint's runs all fall on free cells, with y below
// `y_limit`; false when there is none. A row whose longest free run is shorter than the footprint's
// row there rules out its y; a run that does not fit moves x past the claimed cells it met.
bool first_fit(const Occupancy& atlas, const RowRuns& rows, int width, int y_limit, int& found_x, int& found_y) {
  const int height = int(rows.size());
  std::vector<int> longest(height, 0);
  for (int r = 0; r < height; ++r)
    for (const auto& run : rows[r]) longest[r] = std::max(longest[r], run.second);
  const int narrowest = *std::min_element(longest.begin(), longest.end());
  int first_row = 0;  // the row that failed last: tried first
  for (int y = 0; y + height <= atlas.height && y < y_limit; ++y) {
    int blocked = -1;
    for (int i = 0, r = first_row; i < height && blocked < 0; ++i, r = r + 1 < height ? r + 1 : 0)
      if (atlas.longest[y + r] < longest[r]) blocked = r;
    if (blocked >= 0) {  // an atlas row too full for the footprint's narrowest row rules out every y that covers it
      first_row = blocked;
      if (atlas.longest[y + blocked] < narrowest) y += blocked;
      continue;
    }
    for (int x = 0; x + width <= atlas.width;) {
      int skip = 0;
      for (int i = 0, r = first_row; i < height && !skip; ++i, r = r + 1 < height ? r + 1 : 0) {
        for (const auto& [start, length] : rows[r]) {
          const int v = atlas.run[size_t(y + r) * atlas.width + x + start];
          if (v < length) {
            skip = v > 0 ? v + 1 : -v;
            first_row = r;
            break;
          }
        }
      }
      if (!skip) {
        found_x = x, found_y = y;
        return true;
      }
      x += skip;
    }
  }
  return false;
}

// Bitmap packing at `scale` into a square grid `size` cells a side: each chart (largest first) takes the
// lowest, then leftmost, place where its footprint meets no claimed cell, in the quarter turn that gives
// the lowest place; so charts fill the holes and bays of those placed before them. Sets each chart's
// turn and position; false when a chart does not fit.
bool pack(std::vector<Chart>& charts, const std::vector<int>& order, const Mesh& mesh, float scale, int size,
          int gutter) {
  Occupancy atlas(size, size);
  for (int i : order) {
    Chart& c = charts[i];
    const Footprint fp = footprint(c, mesh, scale, gutter);
    int best_y = size, best_x = 0, best_turn = -1;
    RowRuns best_rows;
    for (int turn = 0; turn < 4; ++turn) {
      const int w = turn % 2 ? fp.height : fp.width, h = turn % 2 ? fp.width : fp.height;
      if (w > size || h > size) continue;
      RowRuns rows = turned_runs(fp, turn);
      int x, y;
      if (first_fit(atlas, rows, w, best_y, x, y) && (y < best_y || (y == best_y && x < best_x)))
        best_y = y, best_x = x, best_turn = turn, best_rows = std::move(rows);
    }
    if (best_turn < 0) return false;
    c.quarter_turns = best_turn, c.x = best_x, c.y = best_y;
    for (int r = 0; r < int(best_rows.size()); ++r)
      for (const auto& [start, length] : best_rows[r]) atlas.claim_row(best_y + r, best_x + start, length);
  }
  return true;
}

}  // namespace

UvAtlas axis_chart_atlas(const Mesh& mesh, const UvAtlasOptions& options) {
  require(!mesh.faces.empty(), "UV atlas: the mesh has no faces");
  require(options.texture_size >= 16, "UV atlas: texture size must be at least 16");
  require(options.gutter_texels >= 0, "UV atlas: gutter must not be negative");
  const size_t nf = mesh.faces.size();
  const std::vector<Vec3f> normals = face_normals(mesh.positions, mesh.faces);
  const std::vector<std::array<int, 3>> neighbours = face_neighbours(mesh);

  // Labels: the axis each face faces most, then majority smoothing.
  std::vector<int> label(nf);
  for (size_t f = 0; f < nf; ++f) {
    float best = -INFINITY;
    for (int a = 0; a < 6; ++a)
      if (normals[f].dot(kAxes[a].dir) > best) best = normals[f].dot(kAxes[a].dir), label[f] = a;
  }
  for (int round = 0; round < 3; ++round) {
    std::vector<int> next = label;
    for (size_t f = 0; f < nf; ++f) {
      const std::array<int, 3>& n = neighbours[f];
      for (int k = 0; k < 3; ++k) {
        if (n[k] < 0 || label[n[k]] == label[f]) continue;
        const int candidate = label[n[k]];
        const int agree = (n[0] >= 0 && label[n[0]] == candidate) + (n[1] >= 0 && label[n[1]] == candidate) +
                          (n[2] >= 0 && label[n[2]] == candidate);
        if (agree >= 2 && normals[f].dot(kAxes[candidate].dir) > options.min_axis_cos) {
          next[f] = candidate;
          break;
        }
      }
    }
    label.swap(next);
  }
  // Small islands (fewer than min_chart_faces) join the neighbouring label they share most edges
  // with, when all their faces face that axis by more than min_axis_cos.
  for (int round = 0; round < 3; ++round) {
    DisjointSets sets(nf);
    for (size_t f = 0; f < nf; ++f)
      for (int n : neighbours[f])
        if (n >= 0 && label[n] == label[f]) sets.unite(int(f), n);
    std::vector<int> island_size(nf, 0);
    for (size_t f = 0; f < nf; ++f) ++island_size[sets.find(int(f))];
    std::vector<std::array<int, 6>> border_edges(nf, std::array<int, 6>{});  // per island root, per label
    for (size_t f = 0; f < nf; ++f) {
      const int root = sets.find(int(f));
      if (island_size[root] >= options.min_chart_faces) continue;
      for (int n : neighbours[f])
        if (n >= 0 && label[n] != label[f]) ++border_edges[root][label[n]];
    }
    std::vector<int> target(nf, -1);  // per island root, the label it joins
    for (size_t f = 0; f < nf; ++f) {
      const int root = sets.find(int(f));
      if (int(f) != root || island_size[root] >= options.min_chart_faces) continue;
      const auto& counts = border_edges[root];
      const int best = int(std::max_element(counts.begin(), counts.end()) - counts.begin());
      if (counts[best] > 0) target[root] = best;
    }
    std::vector<uint8_t> allowed(nf, 1);
    for (size_t f = 0; f < nf; ++f) {
      const int root = sets.find(int(f));
      if (target[root] >= 0 && normals[f].dot(kAxes[target[root]].dir) <= options.min_axis_cos) allowed[root] = 0;
    }
    bool changed = false;
    for (size_t f = 0; f < nf; ++f) {
      const int root = sets.find(int(f));
      if (target[root] >= 0 && allowed[root]) label[f] = target[root], changed = true;
    }
    if (!changed) break;
  }

  // Charts: connected pieces of each label, split while they overlap themselves.
  std::vector<int> slot(nf, -1);
  std::vector<Chart> pending;
  for (int a = 0; a < 6; ++a) {
    std::vector<int> faces;
    for (size_t f = 0; f < nf; ++f)
      if (label[f] == a) faces.push_back(int(f));
    for (std::vector<int>& piece : connected_pieces(faces, neighbours, slot)) {
      Chart c;
      c.axis = a;
      c.faces = std::move(piece);
      measure(c, mesh);
      pending.push_back(std::move(c));
    }
  }
  float surface_area = 0.f;
  for (const Chart& c : pending) surface_area += c.area * c.stretch * c.stretch;
  require(surface_area > 0.f, "UV atlas: the mesh has zero area");
  // No packing is denser than one that fills the atlas: overlaps are looked for at that scale.
  const float full_scale = float(options.texture_size) / std::sqrt(surface_area);
  std::vector<Chart> charts;
  while (!pending.empty()) {
    Chart c = std::move(pending.back());
    pending.pop_back();
    // A chart that overlaps itself is cut at its median depth along its axis. A chart with more than
    // sprawl_share of the surface that fills less than 0.6 of its bounding rectangle (an outstretched
    // limb, a T), or one longer than half the atlas's side at the scale that would fill the atlas (a
    // pole), is cut across its longer side at its median, so that it packs.
    std::vector<float> key(c.faces.size());
    const bool overlaps = !c.flat && self_overlaps(c, mesh, full_scale * c.stretch);
    const float share = c.area * c.stretch * c.stretch / surface_area;
    if (overlaps) {
      const Vec3f& dir = kAxes[c.axis].dir;
      for (size_t i = 0; i < c.faces.size(); ++i) {
        const Vec3i& t = mesh.faces[c.faces[i]];
        key[i] = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]).dot(dir);
      }
    } else if (c.faces.size() > 1 && ((share > options.sprawl_share && c.area < 0.6f * c.size.prod()) ||
                                      c.size.maxCoeff() * c.stretch * full_scale > 0.5f * float(options.texture_size))) {
      const int side = c.size.x() >= c.size.y() ? 0 : 1;
      for (size_t i = 0; i < c.faces.size(); ++i) {
        const Vec3i& t = mesh.faces[c.faces[i]];
        key[i] = (project(mesh.positions[t[0]], c) + project(mesh.positions[t[1]], c) +
                  project(mesh.positions[t[2]], c))[side];
      }
    } else {
      charts.push_back(std::move(c));
      continue;
    }
    std::vector<float> sorted = key;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const float median = sorted[sorted.size() / 2];
    std::array<std::vector<int>, 2> halves;
    for (size_t i = 0; i < c.faces.size(); ++i) halves[key[i] < median].push_back(c.faces[i]);
    if (halves[0].empty() || halves[1].empty()) {  // equal keys: split by face order instead
      halves[0].assign(c.faces.begin(), c.faces.begin() + long(c.faces.size() / 2));
      halves[1].assign(c.faces.begin() + long(c.faces.size() / 2), c.faces.end());
    }
    for (const std::vector<int>& half : halves)
      for (std::vector<int>& piece : connected_pieces(half, neighbours, slot)) {
        Chart part;
        part.axis = c.axis;
        part.flat = !overlaps;
        part.faces = std::move(piece);
        measure(part, mesh);
        pending.push_back(std::move(part));
      }
  }

  // Packing, largest charts first, on a grid of at most 1024 cells a side (2 x 2 texels a cell at 2048;
  // gutters rounded up to whole cells), at the largest scale (to 0.5 %) at which every chart fits.
  std::vector<int> order(charts.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const float area_a = charts[a].area * charts[a].stretch * charts[a].stretch,
                area_b = charts[b].area * charts[b].stretch * charts[b].stretch;
    return area_a != area_b ? area_a > area_b : a < b;
  });
  const int cell = std::max(1, options.texture_size / 1024);
  const int size = options.texture_size / cell, gutter = (options.gutter_texels + cell - 1) / cell;
  require(pack(charts, order, mesh, 0.f, size, gutter),
          "UV atlas: a " + std::to_string(options.texture_size) + " texture has no room for the gutters of " +
              std::to_string(charts.size()) + " charts (use a larger texture or fewer faces)");
  struct Placement {
    int quarter_turns, x, y;
  };
  std::vector<Placement> placed;
  auto keep = [&] {
    placed.clear();
    for (const Chart& c : charts) placed.push_back({c.quarter_turns, c.x, c.y});
  };
  // From 0.92 of the scale that would fill the atlas down in steps of 3 % until the charts fit (they do at
  // scale 0), then bisection. Greedy packing is not monotonic in the scale: the steps find a larger scale
  // that fits than bisecting from the start would.
  float lo = 0.f, hi = full_scale / float(cell);
  for (float scale = 0.92f * hi; lo == 0.f; scale *= 0.97f)
    if (pack(charts, order, mesh, scale, size, gutter)) lo = scale, keep();
    else hi = scale;
  while (hi - lo > 0.005f * hi) {
    const float scale = 0.5f * (lo + hi);
    if (pack(charts, order, mesh, scale, size, gutter)) lo = scale, keep();
    else hi = scale;
  }
  for (size_t i = 0; i < charts.size(); ++i)
    charts[i].quarter_turns = placed[i].quarter_turns, charts[i].x = placed[i].x, charts[i].y = placed[i].y;

  // Vertices split per chart, UVs from the packed projection.
  UvAtlas atlas;
  atlas.chart_count = int(charts.size());
  atlas.texels_per_unit = lo * float(cell);
  atlas.face_chart.assign(nf, -1);
  atlas.mesh.faces.resize(nf);
  std::vector<std::vector<std::pair<int, int>>> copies(mesh.positions.size());  // (chart, atlas vertex)
  double covered_area = 0.0;
  for (size_t ci = 0; ci < charts.size(); ++ci) {
    const Chart& c = charts[ci];
    covered_area += double(c.area) * c.stretch * c.stretch;
    const Eigen::Vector2i cells = chart_cells(c, lo);
    const float w = float(cells.x() + gutter), h = float(cells.y() + gutter);
    for (int f : c.faces) {
      atlas.face_chart[f] = int(ci);
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.faces[f][k];
        int id = -1;
        for (const auto& [chart, copy] : copies[v])
          if (chart == int(ci)) id = copy;
        if (id < 0) {
          id = int(atlas.mesh.positions.size());
          copies[v].push_back({int(ci), id});
          atlas.mesh.positions.push_back(mesh.positions[v]);
          if (mesh.has_colors()) atlas.mesh.colors.push_back(mesh.colors[v]);
          atlas.source_vertex.push_back(v);
          const Vec2f p = (project(mesh.positions[v], c) - c.min) * (lo * c.stretch) + Vec2f::Constant(float(gutter / 2));
          const Vec2f turned = c.quarter_turns == 0   ? p
                               : c.quarter_turns == 1 ? Vec2f(h - p.y(), p.x())
                               : c.quarter_turns == 2 ? Vec2f(w - p.x(), h - p.y())
                                                      : Vec2f(p.y(), w - p.x());
          atlas.mesh.uvs.push_back((turned + Vec2f(float(c.x), float(c.y))) / float(size));
        }
        atlas.mesh.faces[f][k] = id;
      }
    }
  }
  atlas.texel_efficiency = float(covered_area * lo * lo / (double(size) * size));
  return atlas;
}

}  // namespace u3d
