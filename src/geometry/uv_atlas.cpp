#include "geometry/uv_atlas.h"

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
  bool rotated = false;         // turned a quarter (counter-clockwise) so it is at least as wide as tall
  Vec2f min{0, 0}, size{0, 0};  // bounding box of the (turned) projection, world units
  float area = 0.f;             // projected area, world units squared
  Vec2f origin{0, 0};           // packed position of the bounding box's corner, texels
};

Vec2f project(const Vec3f& p, const Chart& c) {
  const Axis& a = kAxes[c.axis];
  const Vec2f q(p.dot(a.right), p.dot(a.up));
  return c.rotated ? Vec2f(-q.y(), q.x()) : q;
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

// Bounding box and projected area of a chart (after choosing its turn).
void measure(Chart& c, const Mesh& mesh) {
  c.rotated = false;
  for (int pass = 0; pass < 2; ++pass) {
    Vec2f lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
    c.area = 0.f;
    for (int f : c.faces) {
      const Vec3i& t = mesh.faces[f];
      const Vec2f a = project(mesh.positions[t[0]], c), b = project(mesh.positions[t[1]], c),
                  d = project(mesh.positions[t[2]], c);
      lo = lo.cwiseMin(a).cwiseMin(b).cwiseMin(d);
      hi = hi.cwiseMax(a).cwiseMax(b).cwiseMax(d);
      const Vec2f u = b - a, v = d - a;
      c.area += 0.5f * std::abs(u.x() * v.y() - u.y() * v.x());
    }
    c.min = lo;
    c.size = hi - lo;
    if (pass == 0 && c.size.y() > c.size.x())
      c.rotated = true;
    else
      break;
  }
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
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
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
  return false;
}

// Shelf packing at `scale`: sets each chart's origin; false when the charts do not fit.
bool pack(std::vector<Chart>& charts, const std::vector<int>& order, float scale, int size, int gutter) {
  float x = 0.f, y = 0.f, shelf = 0.f;
  for (int i : order) {
    Chart& c = charts[i];
    const float w = std::ceil(c.size.x() * scale) + 1.f + float(gutter),
                h = std::ceil(c.size.y() * scale) + 1.f + float(gutter);
    if (w > float(size)) return false;
    if (x + w > float(size)) y += shelf, x = 0.f, shelf = 0.f;
    if (y + h > float(size)) return false;
    c.origin = Vec2f(x, y);
    x += w;
    shelf = std::max(shelf, h);
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
  float total_area = 0.f;
  for (const Chart& c : pending) total_area += c.area;
  require(total_area > 0.f, "UV atlas: the mesh has zero area");
  // Overlaps are looked for at the scale a packing that fills 60 % of the atlas would have.
  const float check_scale = std::sqrt(0.6f * float(options.texture_size) * float(options.texture_size) / total_area);
  std::vector<Chart> charts;
  while (!pending.empty()) {
    Chart c = std::move(pending.back());
    pending.pop_back();
    if (!self_overlaps(c, mesh, check_scale)) {
      charts.push_back(std::move(c));
      continue;
    }
    const Vec3f& dir = kAxes[c.axis].dir;
    std::vector<float> depth(c.faces.size());
    for (size_t i = 0; i < c.faces.size(); ++i) {
      const Vec3i& t = mesh.faces[c.faces[i]];
      depth[i] = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]).dot(dir);
    }
    std::vector<float> sorted = depth;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const float median = sorted[sorted.size() / 2];
    std::array<std::vector<int>, 2> halves;
    for (size_t i = 0; i < c.faces.size(); ++i) halves[depth[i] < median].push_back(c.faces[i]);
    if (halves[0].empty() || halves[1].empty()) {  // equal depths: split by face order instead
      halves[0].assign(c.faces.begin(), c.faces.begin() + long(c.faces.size() / 2));
      halves[1].assign(c.faces.begin() + long(c.faces.size() / 2), c.faces.end());
    }
    for (const std::vector<int>& half : halves)
      for (std::vector<int>& piece : connected_pieces(half, neighbours, slot)) {
        Chart part;
        part.axis = c.axis;
        part.faces = std::move(piece);
        measure(part, mesh);
        pending.push_back(std::move(part));
      }
  }

  // Packing: the largest scale at which every chart fits.
  std::vector<int> order(charts.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return charts[a].size.y() != charts[b].size.y() ? charts[a].size.y() > charts[b].size.y() : a < b;
  });
  const int size = options.texture_size, gutter = options.gutter_texels;
  float largest = 0.f;
  for (const Chart& c : charts) largest = std::max({largest, c.size.x(), c.size.y()});
  require(pack(charts, order, 0.f, size, gutter),
          "UV atlas: a " + std::to_string(size) + " texture has no room for the gutters of " +
              std::to_string(charts.size()) + " charts (use a larger texture or fewer faces)");
  float lo = 0.f, hi = largest > 0.f ? float(size) / largest : 1.f;
  for (int i = 0; i < 40; ++i) {
    const float mid = 0.5f * (lo + hi);
    (pack(charts, order, mid, size, gutter) ? lo : hi) = mid;
  }
  pack(charts, order, lo, size, gutter);

  // Vertices split per chart, UVs from the packed projection.
  UvAtlas atlas;
  atlas.chart_count = int(charts.size());
  atlas.texels_per_unit = lo;
  atlas.face_chart.assign(nf, -1);
  atlas.mesh.faces.resize(nf);
  std::vector<std::vector<std::pair<int, int>>> copies(mesh.positions.size());  // (chart, atlas vertex)
  const float half_gutter = 0.5f * float(gutter);
  float covered_area = 0.f;
  for (size_t ci = 0; ci < charts.size(); ++ci) {
    const Chart& c = charts[ci];
    covered_area += c.area;
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
          const Vec2f texel = c.origin + Vec2f(half_gutter, half_gutter) + (project(mesh.positions[v], c) - c.min) * lo;
          atlas.mesh.uvs.push_back(texel / float(size));
        }
        atlas.mesh.faces[f][k] = id;
      }
    }
  }
  atlas.texel_efficiency = covered_area * lo * lo / (float(size) * float(size));
  return atlas;
}

}  // namespace u3d
