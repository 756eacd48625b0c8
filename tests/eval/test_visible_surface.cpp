// Visibility of surface samples from outside: what the visible-surface completeness and recall leave out.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/error.h"
#include "core/progress.h"
#include "eval/evaluate.h"
#include "eval/visible_surface.h"
#include "geometry/test_shapes.h"

using namespace u3d;

namespace {

// Appends `part` to `m` (shared nothing).
void append(Mesh& m, const Mesh& part) {
  const int offset = int(m.positions.size());
  m.positions.insert(m.positions.end(), part.positions.begin(), part.positions.end());
  for (const Vec3i& f : part.faces) m.faces.push_back(f + Vec3i::Constant(offset));
}

// Square of half side `h` in the plane y = `y` (two triangles facing +y).
Mesh square_y(float h, float y) {
  Mesh m;
  m.positions = {{-h, y, -h}, {h, y, -h}, {h, y, h}, {-h, y, h}};
  m.faces = {{0, 2, 1}, {0, 3, 2}};
  return m;
}

}  // namespace

TEST(VisibleSurface, DirectionsAreUnitSpreadAndAvoidThePoles) {
  const std::vector<Vec3f> dirs = sphere_directions(64);
  ASSERT_EQ(dirs.size(), 64u);
  Vec3f sum = Vec3f::Zero();
  for (const Vec3f& d : dirs) {
    EXPECT_NEAR(d.norm(), 1.f, 1e-5f);
    EXPECT_LT(std::abs(d.y()), 0.999f);
    sum += d;
  }
  EXPECT_LT(sum.norm() / 64.f, 0.05f);
  EXPECT_THROW(sphere_directions(0), Error);
}

TEST(VisibleSurface, EverySampleOfASphereIsSeen) {
  const Mesh sphere = test::sphere_mesh(0.5f, 3);
  const SurfaceSamples s = sample_surface(sphere.positions, sphere.faces, 20000, 3);
  const std::vector<uint8_t> seen = visible_from_outside(sphere, s);
  EXPECT_EQ(std::count(seen.begin(), seen.end(), uint8_t(1)), 20000);
}

TEST(VisibleSurface, AFaceInsideABoxIsHiddenAndTheBoxIsNot) {
  Mesh m = test::box_mesh(Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f));
  const size_t box_faces = m.faces.size();
  append(m, square_y(0.4f, 0.f));
  const SurfaceSamples s = sample_surface(m.positions, m.faces, 20000, 4);
  const std::vector<uint8_t> seen = visible_from_outside(m, s);
  size_t inner = 0;
  for (size_t i = 0; i < seen.size(); ++i) {
    const bool on_box = size_t(s.faces[i]) < box_faces;
    EXPECT_EQ(seen[i], on_box ? 1 : 0) << "sample " << i << " at " << s.points[i].transpose();
    inner += !on_box;
  }
  EXPECT_GT(inner, 1000u);
}

TEST(VisibleSurface, AFaceIsHiddenOnlyWhereABlockStandsOnIt) {
  // The avocado's case: the top of a slab runs on under a closed block that stands on it.
  Mesh m = test::box_mesh(Vec3f(-0.5f, -0.3f, -0.5f), Vec3f(0.5f, 0.f, 0.5f));
  append(m, test::box_mesh(Vec3f(-0.2f, 0.f, -0.2f), Vec3f(0.2f, 0.3f, 0.2f)));
  const SurfaceSamples s = sample_surface(m.positions, m.faces, 20000, 5);
  const std::vector<uint8_t> seen = visible_from_outside(m, s);
  size_t under = 0, around = 0;
  for (size_t i = 0; i < seen.size(); ++i) {
    const Vec3f& p = s.points[i];
    const float r = std::max(std::abs(p.x()), std::abs(p.z()));
    const bool on_top = std::abs(p.y()) < 1e-5f;  // the slab's top or the block's bottom
    if (on_top && r < 0.19f) {
      EXPECT_EQ(seen[i], 0) << p.transpose();
      ++under;
    } else if (!on_top || r > 0.21f) {
      EXPECT_EQ(seen[i], 1) << p.transpose();
      around += on_top;
    }
  }
  EXPECT_GT(under, 1000u);
  EXPECT_GT(around, 2000u);
}

TEST(VisibleSurface, EvaluationLeavesHiddenGtSurfaceOutOfRecallOnly) {
  set_progress_quiet(true);
  Mesh pred = test::box_mesh(Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f));
  Mesh gt = pred;
  append(gt, square_y(0.4f, 0.f));  // at least 0.1 from the box everywhere
  EvalOptions o;
  o.surface_samples = 20000;
  o.fscore_thresholds = {0.05f};
  o.iou_resolution = 16;
  o.appearance = false;
  const EvalReport r = evaluate_meshes(pred, gt, o);
  // Inner square area 0.64 of 6.64 in all.
  EXPECT_NEAR(double(r.gt_hidden_samples) / 20000.0, 0.64 / 6.64, 0.01);
  EXPECT_NEAR(r.fscores[0].recall, 6.0 / 6.64, 0.01);
  EXPECT_DOUBLE_EQ(r.fscores_visible[0].recall, 1.0);
  EXPECT_DOUBLE_EQ(r.fscores_visible[0].precision, r.fscores[0].precision);
  EXPECT_LT(r.chamfer_visible.completeness, 1e-6);
  EXPECT_GT(r.chamfer.completeness, 0.01);
}

TEST(VisibleSurface, RejectsAnEmptyMesh) {
  EXPECT_THROW(visible_from_outside(Mesh{}, SurfaceSamples{}), Error);
}
