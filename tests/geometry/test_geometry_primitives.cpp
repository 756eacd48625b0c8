// Surface sampling, closest points and winding numbers: the building blocks of the geometry metrics.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "geometry/surface_sampling.h"
#include "geometry/test_shapes.h"
#include "geometry/triangle_bvh.h"
#include "geometry/triangle_split.h"
#include "geometry/winding_number.h"

using namespace u3d;

TEST(SurfaceSampling, PointsLieOnTheSurfaceAndFollowArea) {
  // Box 2 x 1 x 1: the two x-facing sides hold 2 of the 10 area units.
  Mesh box = test::box_mesh({0, 0, 0}, {2, 1, 1});
  EXPECT_DOUBLE_EQ(surface_area(box.positions, box.faces), 10.0);
  SurfaceSamples s = sample_surface(box.positions, box.faces, 20000, 7);
  ASSERT_EQ(s.points.size(), 20000u);
  size_t on_x_sides = 0;
  for (const auto& p : s.points) {
    Vec3f to_lo = p, to_hi = Vec3f(2, 1, 1) - p;
    float gap = std::min(to_lo.cwiseAbs().minCoeff(), to_hi.cwiseAbs().minCoeff());
    EXPECT_LT(gap, 1e-5f);
    EXPECT_TRUE((p.array() >= -1e-6f).all() && (p.array() <= Eigen::Array3f(2, 1, 1) + 1e-6f).all());
    if (std::abs(p.x()) < 1e-6f || std::abs(p.x() - 2) < 1e-6f) ++on_x_sides;
  }
  EXPECT_NEAR(double(on_x_sides) / 20000.0, 0.2, 0.015);
}

TEST(SurfaceSampling, IsDeterministicPerSeedAndSkipsZeroAreaFaces) {
  Mesh box = test::box_mesh({0, 0, 0}, {1, 1, 1});
  box.faces.push_back({0, 0, 1});  // zero area: must never be chosen
  SurfaceSamples a = sample_surface(box.positions, box.faces, 1000, 3);
  SurfaceSamples b = sample_surface(box.positions, box.faces, 1000, 3);
  SurfaceSamples c = sample_surface(box.positions, box.faces, 1000, 4);
  EXPECT_EQ(a.points, b.points);
  EXPECT_NE(a.points, c.points);
  for (int f : a.faces) EXPECT_LT(f, 12);
}

TEST(SurfaceSampling, ZeroAreaMeshIsAnError) {
  std::vector<Vec3f> p = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  EXPECT_THROW(sample_surface(p, {{0, 1, 2}}, 10, 0), Error);
}

TEST(TriangleBvh, ClosestPointMatchesBruteForce) {
  Mesh sphere = test::sphere_mesh(0.4f, 3);
  TriangleBvh bvh(sphere.positions, sphere.faces);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int i = 0; i < 300; ++i) {
    Vec3f q(u(rng), u(rng), u(rng));
    float best = INFINITY;
    for (const auto& f : sphere.faces) {
      Vec3f c = closest_point_on_triangle(q, sphere.positions[f[0]], sphere.positions[f[1]], sphere.positions[f[2]]);
      best = std::min(best, (c - q).norm());
    }
    auto hit = bvh.closest_point(q);
    EXPECT_NEAR(hit.distance, best, 1e-6f);
    EXPECT_NEAR((hit.point - q).norm(), hit.distance, 1e-5f);
    EXPECT_NEAR(std::abs(q.norm() - 0.4f), hit.distance, 0.01f);  // faceted sphere ~ true sphere
  }
}

TEST(TriangleBvh, DegenerateTrianglesGiveFiniteDistances) {
  // Collinear, repeated-vertex and single-point triangles: the cases that abort other libraries.
  std::vector<Vec3f> p = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
  std::vector<Vec3i> f = {{0, 1, 2}, {0, 0, 3}, {3, 3, 3}};
  TriangleBvh bvh(p, f);
  auto hit = bvh.closest_point({1.5f, -1, 0});
  EXPECT_FLOAT_EQ(hit.distance, 1.f);
  EXPECT_EQ(hit.face, 0);
  EXPECT_NEAR(bvh.closest_point({0, 2, 0}).distance, 1.f, 1e-6f);
  EXPECT_THROW(TriangleBvh(p, {}), Error);
}

TEST(WindingNumber, InsideOneOutsideZeroAndSignFollowsOrientation) {
  Mesh sphere = test::sphere_mesh(0.5f, 3);
  TriangleBvh bvh(sphere.positions, sphere.faces);
  WindingNumber w(bvh);
  EXPECT_NEAR(w({0, 0, 0}), 1.0, 0.04);
  EXPECT_NEAR(w({0.1f, 0.3f, -0.2f}), 1.0, 0.04);
  EXPECT_NEAR(w({0.7f, 0, 0}), 0.0, 0.04);
  EXPECT_NEAR(w({3, 4, 5}), 0.0, 1e-3);
  Mesh inverted = test::flipped(sphere);
  TriangleBvh bvh_inverted(inverted.positions, inverted.faces);
  EXPECT_NEAR(WindingNumber(bvh_inverted)({0, 0, 0}), -1.0, 0.04);
}

TEST(WindingNumber, HierarchicalApproximationStaysCloseToExact) {
  Mesh sphere = test::sphere_mesh(0.5f, 4);
  TriangleBvh bvh(sphere.positions, sphere.faces);
  WindingNumber w(bvh);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-0.8f, 0.8f);
  for (int i = 0; i < 200; ++i) {
    Vec3f q(u(rng), u(rng), u(rng));
    EXPECT_NEAR(w(q), winding_number_exact(sphere.positions, sphere.faces, q), 0.04) << q.transpose();
  }
}

TEST(WindingNumber, OpenBoxIsStillInsideAtItsCentre) {
  // Removing one side of a cube removes 1/6 of the solid angle seen from the centre.
  Mesh box = test::box_mesh({-1, -1, -1}, {1, 1, 1});
  box.faces.resize(10);
  TriangleBvh bvh(box.positions, box.faces);
  EXPECT_NEAR(WindingNumber(bvh)({0, 0, 0}), 5.0 / 6.0, 1e-6);
}

TEST(TriangleSplit, PiecesTileTheTriangleWithShortEdgesAndTheSameOrientation) {
  // A long sliver (as in fans of surfaces of revolution) and a short triangle that stays as it is.
  std::vector<Vec3f> p = {{0, 0, 0}, {1, 0, 0}, {0.5f, 0.05f, 0.02f}, {0, 0, 1}, {0.01f, 0, 1}, {0, 0.01f, 1}};
  std::vector<Vec3i> f = {{0, 1, 2}, {3, 4, 5}};
  TriangleSoup s = split_long_triangles(p, f, 0.1f);
  EXPECT_GT(s.faces.size(), 10u);
  EXPECT_EQ(s.faces.back(), Vec3i(3, 4, 5));  // short triangles keep their shared vertices
  Eigen::Vector3d area_vector = Eigen::Vector3d::Zero();
  for (size_t i = 0; i + 1 < s.faces.size(); ++i) {
    const auto& t = s.faces[i];
    for (int k = 0; k < 3; ++k) EXPECT_LE((s.positions[t[(k + 1) % 3]] - s.positions[t[k]]).norm(), 0.1f + 1e-6f);
    area_vector += 0.5 * (s.positions[t[1]] - s.positions[t[0]]).cross(s.positions[t[2]] - s.positions[t[0]]).cast<double>();
  }
  Eigen::Vector3d original = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).cast<double>();
  EXPECT_TRUE(area_vector.isApprox(original, 1e-5)) << area_vector.transpose();
}

TEST(TriangleSplit, WindingNumbersAreUnchanged) {
  Mesh box = test::box_mesh({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f});
  TriangleSoup s = split_long_triangles(box.positions, box.faces, 0.2f);
  EXPECT_GT(s.faces.size(), 12u * 16u);
  for (const Vec3f& q : {Vec3f(0, 0, 0), Vec3f(0.45f, -0.3f, 0.2f), Vec3f(0.7f, 0, 0), Vec3f(0.52f, 0.1f, 0.1f)})
    EXPECT_NEAR(winding_number_exact(s.positions, s.faces, q), winding_number_exact(box.positions, box.faces, q), 1e-9);
}
