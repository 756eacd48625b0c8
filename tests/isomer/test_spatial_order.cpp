// Renumbering in space-filling-curve order: the same surface afterwards, rows with their vertices, and
// surface neighbours closer in memory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <tuple>

#include "geometry/icosphere.h"
#include "isomer/remesh/spatial_order.h"

using namespace u3d;

namespace {

// Each face as its three corner positions, rotated so the smallest comes first (winding kept).
std::multiset<std::tuple<float, float, float, float, float, float, float, float, float>> corner_sets(
    const VertexRows& rows, const std::vector<Vec3i>& faces) {
  std::multiset<std::tuple<float, float, float, float, float, float, float, float, float>> out;
  for (const Vec3i& f : faces) {
    std::array<Vec3f, 3> p = {rows.position(f[0]), rows.position(f[1]), rows.position(f[2])};
    auto less = [](const Vec3f& a, const Vec3f& b) { return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z()); };
    while (!(less(p[0], p[1]) && less(p[0], p[2]))) std::rotate(p.begin(), p.begin() + 1, p.end());
    out.insert({p[0].x(), p[0].y(), p[0].z(), p[1].x(), p[1].y(), p[1].z(), p[2].x(), p[2].y(), p[2].z()});
  }
  return out;
}

double mean_index_gap(const std::vector<Vec3i>& faces) {
  double sum = 0;
  for (const Vec3i& f : faces)
    for (int i = 0; i < 3; ++i) sum += std::abs(f[i] - f[(i + 1) % 3]);
  return sum / double(3 * faces.size());
}

// An icosphere whose vertices and faces were shuffled, as many remeshing passes leave them; rows carry
// (x, y, z, tag) with tag = x + 2y + 3z.
void shuffled_sphere(VertexRows& rows, std::vector<Vec3i>& faces) {
  const Mesh m = make_icosphere(4, 0.8f);
  std::vector<int> perm(m.positions.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::mt19937 rng(7);
  std::shuffle(perm.begin(), perm.end(), rng);
  rows.stride = 4;
  rows.values.assign(m.positions.size() * 4, 0.f);
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const Vec3f& p = m.positions[v];
    std::copy_n(std::array<float, 4>{p.x(), p.y(), p.z(), p.x() + 2 * p.y() + 3 * p.z()}.data(), 4,
                rows.row(size_t(perm[v])));
  }
  faces = m.faces;
  for (Vec3i& f : faces)
    for (int i = 0; i < 3; ++i) f[i] = perm[size_t(f[i])];
  std::shuffle(faces.begin(), faces.end(), rng);
}

}  // namespace

TEST(SpatialOrder, KeepsTheSurfaceAndTheRowsAndBringsNeighboursTogether) {
  VertexRows rows;
  std::vector<Vec3i> faces;
  shuffled_sphere(rows, faces);
  const auto before = corner_sets(rows, faces);
  const double gap_before = mean_index_gap(faces);
  const size_t vertices = rows.count(), face_count = faces.size();

  reorder_spatially(rows, faces);
  ASSERT_EQ(rows.count(), vertices);
  ASSERT_EQ(faces.size(), face_count);
  EXPECT_EQ(corner_sets(rows, faces), before);  // same triangles, same winding
  for (size_t v = 0; v < rows.count(); ++v) {
    const float* r = rows.row(v);
    ASSERT_FLOAT_EQ(r[3], r[0] + 2 * r[1] + 3 * r[2]) << "row " << v;
  }
  // Shuffled, an edge joins vertices a third of the mesh apart on average; in Z-order, a few percent.
  EXPECT_GT(gap_before, 0.25 * double(vertices));
  EXPECT_LT(mean_index_gap(faces), 0.05 * double(vertices));
  for (size_t f = 1; f < faces.size(); ++f) ASSERT_LE(faces[f - 1].minCoeff(), faces[f].minCoeff());
}

TEST(SpatialOrder, DependsOnlyOnTheInput) {
  VertexRows a, b;
  std::vector<Vec3i> fa, fb;
  shuffled_sphere(a, fa);
  shuffled_sphere(b, fb);
  reorder_spatially(a, fa);
  reorder_spatially(b, fb);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(fa, fb);
  // Already in order: a second pass changes nothing.
  VertexRows again = a;
  std::vector<Vec3i> fagain = fa;
  reorder_spatially(again, fagain);
  EXPECT_EQ(again.values, a.values);
  EXPECT_EQ(fagain, fa);
}

TEST(SpatialOrder, EmptyFlatAndDivergedMeshesAreFine) {
  VertexRows empty;
  std::vector<Vec3i> none;
  reorder_spatially(empty, none);
  EXPECT_EQ(empty.count(), 0u);
  VertexRows flat;  // all in the plane z = 0: a zero-size box axis must not divide by zero
  flat.values = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  std::vector<Vec3i> quad = {{0, 1, 2}, {1, 3, 2}};
  reorder_spatially(flat, quad);
  for (float x : flat.values) EXPECT_TRUE(std::isfinite(x));
  EXPECT_EQ(flat.count(), 4u);
  flat.values[0] = std::nanf("");  // a diverged vertex still gets a place
  reorder_spatially(flat, quad);
  EXPECT_EQ(flat.count(), 4u);
  EXPECT_EQ(std::count_if(flat.values.begin(), flat.values.end(), [](float x) { return std::isnan(x); }), 1);
}
