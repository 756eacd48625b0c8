// Remeshing keeps a closed, consistently oriented manifold and carries per-vertex rows along.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <random>
#include <string>

#include "geometry/edge_topology.h"
#include "geometry/icosphere.h"
#include "geometry/manifold_check.h"
#include "isomer/remesh/collapse.h"
#include "isomer/remesh/flip.h"
#include "isomer/remesh/remesh.h"
#include "isomer/remesh/split.h"

using namespace u3d;

namespace {

// Rows (x, y, z, tag) with tag == x: every edit averages whole rows, so the tag must keep matching x.
VertexRows tagged_rows(const std::vector<Vec3f>& positions) {
  VertexRows r;
  r.stride = 4;
  for (const Vec3f& p : positions) r.values.insert(r.values.end(), {p.x(), p.y(), p.z(), p.x()});
  return r;
}

double signed_volume(const VertexRows& rows, const std::vector<Vec3i>& faces) {
  double v = 0;
  for (const Vec3i& f : faces) v += rows.position(f[0]).dot(rows.position(f[1]).cross(rows.position(f[2]))) / 6.0;
  return v;
}

// Same edges with the same faces on each side, each face side naming its edge, and the same rings;
// edge numbers may differ (patched topologies keep theirs).
void expect_same_topology(const EdgeTopology& a, const EdgeTopology& b, const std::vector<Vec3i>& faces) {
  auto edges = [](const EdgeTopology& t) {
    std::map<std::array<int, 2>, std::pair<std::array<int, 2>, char>> m;
    for (size_t e = 0; e < t.edge_count(); ++e) m[t.edge_vertices[e]] = {t.edge_sides[e], t.edge_manifold[e]};
    return m;
  };
  EXPECT_EQ(edges(a), edges(b));
  ASSERT_EQ(a.face_edges.size(), faces.size());
  for (size_t f = 0; f < faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      const int u = faces[f][i], v = faces[f][(i + 1) % 3];
      const std::array<int, 2> key = {std::min(u, v), std::max(u, v)};
      ASSERT_EQ(a.edge_vertices[a.face_edges[f][i]], key) << "face " << f << " side " << i;
    }
  ASSERT_EQ(a.ring_offsets, b.ring_offsets);
  for (size_t v = 0; v + 1 < a.ring_offsets.size(); ++v) {
    std::vector<int> ra(a.ring.begin() + a.ring_offsets[v], a.ring.begin() + a.ring_offsets[v + 1]);
    std::vector<int> rb(b.ring.begin() + b.ring_offsets[v], b.ring.begin() + b.ring_offsets[v + 1]);
    std::sort(ra.begin(), ra.end());
    std::sort(rb.begin(), rb.end());
    ASSERT_EQ(ra, rb) << "ring of vertex " << v;
  }
}

int euler_characteristic(const std::vector<Vec3i>& faces, size_t vertices) {
  return int(vertices) - int(build_edge_topology(faces, vertices).edge_count()) + int(faces.size());
}

}  // namespace

TEST(Remesh, SplitOneEdgeOfAnOctahedron) {
  Mesh m = make_icosphere(0, 1.f);
  VertexRows rows = tagged_rows(m.positions);
  std::vector<float> max_len(rows.count(), 10.f);
  max_len[m.faces[0][0]] = max_len[m.faces[0][1]] = 0.1f;  // only the edge between them is "long"
  std::vector<Vec3i> faces = m.faces;
  EXPECT_EQ(split_long_edges(rows, faces, build_edge_topology(faces, rows.count()), max_len), 1);
  EXPECT_EQ(rows.count(), 13u);
  EXPECT_EQ(faces.size(), 22u);
  EXPECT_EQ(closed_manifold_problem(faces, rows.count()), "");
  const Vec3f mid = 0.5f * (m.positions[m.faces[0][0]] + m.positions[m.faces[0][1]]);
  EXPECT_TRUE(rows.position(12).isApprox(mid));
}

TEST(Remesh, CollapseRemovesShortEdgesAndKeepsTheManifold) {
  Mesh m = make_icosphere(2, 1.f);
  VertexRows rows = tagged_rows(m.positions);
  std::vector<Vec3i> faces = m.faces;
  std::mt19937 rng(1);
  const std::vector<float> min_len(rows.count(), 0.5f);  // every edge (~0.3) is short
  const int collapses = collapse_short_edges(rows, faces, build_edge_topology(faces, rows.count()), min_len, rng);
  EXPECT_GT(collapses, 10);
  drop_unreferenced_vertices(rows, faces);
  EXPECT_EQ(rows.count(), m.vertex_count() - collapses);
  EXPECT_EQ(closed_manifold_problem(faces, rows.count()), "");
}

TEST(Remesh, FlipsLowerValenceSpread) {
  // A sphere with irregular valences: split a few random edges (creates valence-4 vertices).
  Mesh m = make_icosphere(2, 1.f);
  VertexRows rows = tagged_rows(m.positions);
  std::vector<Vec3i> faces = m.faces;
  std::vector<float> max_len(rows.count(), 0.5f);  // edges are ~0.33 long
  for (int v = 0; v < 40; v += 7) max_len[v] = 0.f;  // split the edges around these vertices
  split_long_edges(rows, faces, build_edge_topology(faces, rows.count()), max_len);
  auto spread = [&] {
    EdgeTopology t = build_edge_topology(faces, rows.count());
    int s = 0;
    for (size_t v = 0; v < rows.count(); ++v) s += (t.degree(int(v)) - 6) * (t.degree(int(v)) - 6);
    return s;
  };
  const int before = spread();
  EdgeTopology t = build_edge_topology(faces, rows.count());
  EXPECT_GT(flip_edges_for_valence(rows, faces, t), 0);
  EXPECT_LT(spread(), before);
  EXPECT_EQ(closed_manifold_problem(faces, rows.count()), "");
  // The topology patched by the flips is the flipped faces' own.
  expect_same_topology(t, build_edge_topology(faces, rows.count()), faces);
}

// Many random rounds of collapse / split / flip with random target lengths and jittered positions.
TEST(Remesh, RandomRoundsKeepClosedOrientedManifoldAndRowsFollowVertices) {
  Mesh m = make_icosphere(2, 0.8f);
  VertexRows rows = tagged_rows(m.positions);
  std::vector<Vec3i> faces = m.faces;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  int total_collapses = 0, total_splits = 0, total_flips = 0;
  TopologyCache cache;  // kept across rounds, as the optimizer keeps it
  for (int round = 0; round < 150; ++round) {
    // Jitter positions (tag moves with x), then remesh toward a random per-vertex length.
    for (size_t v = 0; v < rows.count(); ++v) {
      float* r = rows.row(v);
      const Vec3f p = rows.position(v);
      const Vec3f d = 0.01f * Vec3f(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f) + 0.002f * p.normalized();
      r[0] += d.x(), r[1] += d.y(), r[2] += d.z(), r[3] += d.x();
    }
    const float base = 0.08f + 0.25f * unit(rng);
    std::vector<float> ref(rows.count());
    for (float& x : ref) x = base * (0.7f + 0.6f * unit(rng));
    std::vector<float> min_len(ref), max_len(ref);
    for (float& x : min_len) x *= 0.5f;
    for (float& x : max_len) x *= 1.5f;
    const RemeshCounts c = remesh_pass(rows, faces, min_len, max_len, true, rng, 1000000, &cache);
    total_collapses += c.collapses, total_splits += c.splits, total_flips += c.flips;
    if (round % 10 == 0) {
      SCOPED_TRACE("round " + std::to_string(round));
      expect_same_topology(cache.of(faces, rows.count()), build_edge_topology(faces, rows.count()), faces);
    }
    ASSERT_EQ(closed_manifold_problem(faces, rows.count()), "") << "round " << round;
    ASSERT_EQ(euler_characteristic(faces, rows.count()), 2) << "round " << round;
    ASSERT_GT(signed_volume(rows, faces), 0.0) << "round " << round;
    for (size_t v = 0; v < rows.count(); ++v) ASSERT_NEAR(rows.row(v)[3], rows.row(v)[0], 1e-4f) << "round " << round;
  }
  EXPECT_GT(total_collapses, 500);
  EXPECT_GT(total_splits, 500);
  EXPECT_GT(total_flips, 100);
}
