// The complete evaluation: frames, warnings for imperfect input, errors for unusable input, JSON.
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/progress.h"
#include "eval/eval_report.h"
#include "eval/evaluate.h"
#include "geometry/test_shapes.h"

using namespace u3d;

namespace {

EvalOptions quick_options() {
  EvalOptions o;
  o.surface_samples = 5000;
  o.iou_resolution = 24;
  o.appearance_options = {48, 1};
  return o;
}

Mesh colored_sphere() {
  Mesh m = test::sphere_mesh(0.5f, 2);
  for (const auto& p : m.positions) m.colors.push_back((p + Vec3f::Constant(0.5f)).cwiseMin(1.f).cwiseMax(0.f));
  return m;
}

}  // namespace

TEST(Evaluate, IdenticalMeshesGetPerfectScores) {
  set_progress_quiet(true);
  Mesh m = colored_sphere();
  EvalReport r = evaluate_meshes(m, m, quick_options());
  EXPECT_LT(r.chamfer.chamfer_l1, 1e-6);
  EXPECT_DOUBLE_EQ(r.iou.iou, 1.0);
  ASSERT_EQ(r.fscores.size(), 3u);
  for (const auto& f : r.fscores) EXPECT_DOUBLE_EQ(f.fscore, 1.0);
  ASSERT_TRUE(r.appearance.has_value());
  EXPECT_NEAR(r.appearance->psnr, 100.0, 1e-9);
  EXPECT_NEAR(r.appearance->ssim, 1.0, 1e-9);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(Evaluate, NormalizationRemovesScaleAndOffsetButTheGivenFrameKeepsThem) {
  set_progress_quiet(true);
  Mesh gt = colored_sphere(), pred = gt;
  for (auto& p : pred.positions) p = 3.f * p + Vec3f(1, 2, 3);
  EvalOptions o = quick_options();
  o.appearance = false;
  EvalReport normalized = evaluate_meshes(pred, gt, o);
  EXPECT_LT(normalized.chamfer.chamfer_l1, 1e-5);
  EXPECT_DOUBLE_EQ(normalized.iou.iou, 1.0);
  o.normalize = false;
  EvalReport given = evaluate_meshes(pred, gt, o);
  EXPECT_GT(given.chamfer.chamfer_l1, 1.0);
  EXPECT_EQ(given.iou.iou, 0.0);
  EXPECT_FALSE(given.appearance.has_value());
}

TEST(Evaluate, SharedFrameCanPlaceTheGtLikeTheRenderer) {
  set_progress_quiet(true);
  // A perfect reconstruction from views rendered with fill 0.9 comes out 1.8 times the GT's unit size.
  Mesh gt = colored_sphere(), pred = gt;
  for (auto& p : gt.positions) p = 0.25f * p + Vec3f(5, 0, 0);
  normalize_to_unit_box(pred, 0.9f);
  EvalOptions o = quick_options();
  o.appearance = false;
  o.normalize = false;
  o.gt_render_fill = 0.9f;
  EvalReport r = evaluate_meshes(pred, gt, o);
  EXPECT_LT(r.chamfer.chamfer_l1, 1e-5);
  EXPECT_DOUBLE_EQ(r.iou.iou, 1.0);
  // Half a unit off along x in the render frame is d = 0.5 / 1.8 in the evaluation frame; the mean
  // distance of a sphere displaced by d (< radius) to the original is exactly d / 2.
  for (auto& p : pred.positions) p.x() += 0.5f;
  EXPECT_NEAR(evaluate_meshes(pred, gt, o).chamfer.accuracy, 0.25 / 1.8, 0.005);
  o.normalize = true;
  EXPECT_THROW(evaluate_meshes(pred, gt, o), Error);
}

TEST(Evaluate, OpenAndColorlessMeshesAreWarnedAbout) {
  set_progress_quiet(true);
  Mesh gt = colored_sphere(), pred = test::sphere_mesh(0.5f, 2);
  pred.faces.resize(pred.faces.size() - 10);
  EvalReport r = evaluate_meshes(pred, gt, quick_options());
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_NE(r.warnings[0].find("not closed"), std::string::npos);
  EXPECT_NE(r.warnings[1].find("no colour"), std::string::npos);
  EXPECT_GT(r.iou.iou, 0.9);
}

TEST(Evaluate, EmptyOrBrokenMeshesAreErrors) {
  set_progress_quiet(true);
  Mesh good = colored_sphere();
  EXPECT_THROW(evaluate_meshes(Mesh{}, good, quick_options()), Error);
  Mesh bad = good;
  bad.faces.push_back({0, 1, int(bad.positions.size())});
  EXPECT_THROW(evaluate_meshes(good, bad, quick_options()), Error);
  EvalOptions o = quick_options();
  o.fscore_thresholds = {-1.f};
  EXPECT_THROW(evaluate_meshes(good, good, o), Error);
}

TEST(EvalReport, JsonAndSummaryCarryEveryMetric) {
  set_progress_quiet(true);
  Mesh m = colored_sphere();
  EvalReport r = evaluate_meshes(m, m, quick_options());
  nlohmann::json j = report_to_json(r);
  EXPECT_EQ(j["frame"], "normalized");
  EXPECT_DOUBLE_EQ(j["volume_iou"]["iou"].get<double>(), 1.0);
  EXPECT_EQ(j["fscore"].size(), 3u);
  EXPECT_EQ(j["appearance"]["views"].size(), 24u);
  EXPECT_EQ(j["pred"]["faces"].get<size_t>(), m.face_count());
  std::string s = report_summary(r);
  for (const char* key : {"Chamfer-L1", "F-score@0.05", "volume IoU", "PSNR", "SSIM"})
    EXPECT_NE(s.find(key), std::string::npos) << key;
}
