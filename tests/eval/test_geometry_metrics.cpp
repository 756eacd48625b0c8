// Chamfer distance, F-score and volume IoU against closed-form answers.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "eval/chamfer.h"
#include "eval/fscore.h"
#include "eval/mesh_checks.h"
#include "eval/volume_iou.h"
#include "geometry/test_shapes.h"

using namespace u3d;

TEST(Chamfer, ConcentricSpheresAreTheirRadiusGapApart) {
  // Every point of one sphere is exactly |r1 - r2| from the other: CD-L1 = gap, CD-L2 = gap^2.
  Mesh inner = test::sphere_mesh(0.3f, 4), outer = test::sphere_mesh(0.4f, 4);
  ChamferDistance cd = chamfer_distance(surface_distances(inner, outer, 20000, 1));
  EXPECT_NEAR(cd.accuracy, 0.1, 1e-3);
  EXPECT_NEAR(cd.completeness, 0.1, 1e-3);
  EXPECT_NEAR(cd.chamfer_l1, 0.1, 1e-3);
  EXPECT_NEAR(cd.chamfer_l2, 0.01, 2e-4);
}

TEST(Chamfer, IdenticalMeshesHaveZeroDistanceAndFullFScore) {
  Mesh sphere = test::sphere_mesh(0.5f, 3);
  SurfaceDistances d = surface_distances(sphere, sphere, 20000, 5);
  EXPECT_LT(chamfer_distance(d).chamfer_l1, 1e-6);
  FScore f = fscore(d, 0.001f);
  EXPECT_DOUBLE_EQ(f.precision, 1.0);
  EXPECT_DOUBLE_EQ(f.recall, 1.0);
  EXPECT_DOUBLE_EQ(f.fscore, 1.0);
}

TEST(FScore, ThresholdBelowAndAboveTheGap) {
  Mesh inner = test::sphere_mesh(0.3f, 4), outer = test::sphere_mesh(0.4f, 4);
  SurfaceDistances d = surface_distances(inner, outer, 5000, 1);
  EXPECT_DOUBLE_EQ(fscore(d, 0.05f).fscore, 0.0);
  EXPECT_DOUBLE_EQ(fscore(d, 0.15f).fscore, 1.0);
}

TEST(FScore, MissingPartLowersRecallOnly) {
  // Prediction = one sphere, GT = two equal spheres far apart: precision 1, recall 1/2, F = 2/3.
  Mesh one = test::sphere_mesh(0.2f, 3);
  Mesh two = one;
  Mesh other = test::sphere_mesh(0.2f, 3, {2, 0, 0});
  for (auto f : other.faces) two.faces.push_back(f + Vec3i::Constant(int(two.positions.size())));
  two.positions.insert(two.positions.end(), other.positions.begin(), other.positions.end());
  FScore f = fscore(surface_distances(one, two, 20000, 2), 0.01f);
  EXPECT_DOUBLE_EQ(f.precision, 1.0);
  EXPECT_NEAR(f.recall, 0.5, 0.02);
  EXPECT_NEAR(f.fscore, 2.0 / 3.0, 0.02);
}

TEST(VolumeIou, ConcentricSpheresMatchTheVolumeRatio) {
  Mesh inner = test::sphere_mesh(0.3f, 4), outer = test::sphere_mesh(0.4f, 4);
  VolumeIou r = volume_iou(inner, outer, 48);
  EXPECT_NEAR(r.iou, std::pow(0.3 / 0.4, 3), 0.01);
  EXPECT_EQ(r.intersection_cells, r.pred_cells);
  EXPECT_EQ(r.union_cells, r.gt_cells);
}

TEST(VolumeIou, CubeAgainstShiftedCube) {
  // Unit cubes overlapping over 0.75 of their length: IoU = 0.75 / 1.25. At resolution 40 the grid
  // over [-0.5, 0.75] x [-0.5, 0.5]^2 has faces exactly on cell borders, so the count is exact.
  Mesh a = test::box_mesh({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f});
  Mesh b = test::box_mesh({-0.25f, -0.5f, -0.5f}, {0.75f, 0.5f, 0.5f});
  EXPECT_NEAR(volume_iou(a, b, 40).iou, 0.6, 1e-9);
  EXPECT_NEAR(volume_iou(a, b, 33).iou, 0.6, 0.03);
}

TEST(VolumeIou, IdenticalFlippedAndOpenMeshes) {
  Mesh sphere = test::sphere_mesh(0.5f, 3);
  EXPECT_DOUBLE_EQ(volume_iou(sphere, sphere, 32).iou, 1.0);
  EXPECT_DOUBLE_EQ(volume_iou(test::flipped(sphere), sphere, 32).iou, 1.0);
  // A cube missing one side: every interior point still sees more than half of the full solid angle
  // (w > 0.5), so the volume is recovered exactly.
  Mesh box = test::box_mesh({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f});
  Mesh open = box;
  open.faces.erase(open.faces.begin() + 6, open.faces.begin() + 8);
  EXPECT_DOUBLE_EQ(volume_iou(open, box, 32).iou, 1.0);
  // Missing two opposite sides (a tube): points near the openings drop below 0.5, the middle does not.
  open.faces.erase(open.faces.begin() + 6, open.faces.begin() + 8);
  double iou = volume_iou(open, box, 32).iou;
  EXPECT_GT(iou, 0.7);
  EXPECT_LT(iou, 1.0);
}

TEST(VolumeIou, FlatMeshEnclosesNothing) {
  Mesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  flat.faces = {{0, 1, 2}};
  VolumeIou r = volume_iou(flat, flat, 16);
  EXPECT_EQ(r.union_cells, 0u);
  EXPECT_EQ(r.iou, 0.0);
  EXPECT_THROW(volume_iou(Mesh{}, flat, 16), Error);
}

TEST(MeshChecks, FindsHolesNonManifoldEdgesAndDegenerateFaces) {
  Mesh box = test::box_mesh({0, 0, 0}, {1, 1, 1});
  EXPECT_TRUE(diagnose_mesh(box).closed());
  EXPECT_TRUE(mesh_warnings(diagnose_mesh(box), "pred").empty());

  Mesh open = box;
  open.faces.pop_back();
  open.faces.pop_back();
  open.faces.push_back({0, 0, 1});
  MeshDiagnostics d = diagnose_mesh(open);
  EXPECT_EQ(d.boundary_edges, 4u);
  EXPECT_EQ(d.degenerate_faces, 1u);
  EXPECT_FALSE(d.closed());
  EXPECT_EQ(mesh_warnings(d, "pred").size(), 2u);

  // Split vertices along a seam (same position, different index) are not a hole.
  Mesh split = box;
  split.positions.push_back(split.positions[0]);
  for (auto& f : split.faces)
    for (int k = 0; k < 3; ++k)
      if (f[k] == 0 && &f - split.faces.data() < 4) f[k] = 8;
  EXPECT_TRUE(diagnose_mesh(split).closed());
}

TEST(MeshChecks, CountsEdgesByHowManyFacesUseThem) {
  Mesh fin;  // a closed tetrahedron with a fin on its edge 1-2: three faces there, two border edges
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  fin.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {1, 2, 4}};
  MeshDiagnostics d = diagnose_mesh(fin);
  EXPECT_EQ(d.nonmanifold_edges, 1u);
  EXPECT_EQ(d.boundary_edges, 2u);
  EXPECT_EQ(mesh_warnings(d, "pred").size(), 2u);

  // Two faces running the same way along 0-1: that edge is neither a border nor non-manifold.
  Mesh same_way;
  same_way.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  same_way.faces = {{0, 1, 2}, {0, 1, 3}};
  d = diagnose_mesh(same_way);
  EXPECT_EQ(d.boundary_edges, 4u);
  EXPECT_EQ(d.nonmanifold_edges, 0u);
}
