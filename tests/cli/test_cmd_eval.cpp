// The eval and perturb subcommands end to end: exit status, outputs, and clear errors on bad input.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/image.h"
#include "core/synthetic_views.h"
#include "geometry/test_shapes.h"
#include "io/mesh_io.h"

using namespace u3d;
namespace fs = std::filesystem;

namespace {

struct CliRun {
  int status;
  std::string output;
};

CliRun run_cli(const std::string& args, const fs::path& dir, bool quiet = true) {
  fs::path log = dir / "cli_output.txt";
  std::string cmd = std::string(UNIQUE3D_CLI) + (quiet ? " --quiet " : " ") + args + " > " + log.string() + " 2>&1";
  int raw = std::system(cmd.c_str());
  std::ifstream f(log);
  std::stringstream ss;
  ss << f.rdbuf();
  return {WEXITSTATUS(raw), ss.str()};
}

class CliEval : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("u3d_test_cli_eval_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path dir;
};

}  // namespace

TEST_F(CliEval, IdenticalMeshesWriteAPerfectJsonReport) {
  Mesh sphere = test::sphere_mesh(0.5f, 2);
  sphere.colors.assign(sphere.positions.size(), Vec3f(0.2f, 0.6f, 0.9f));
  write_mesh(sphere, dir / "a.ply");
  CliRun r = run_cli("eval " + (dir / "a.ply").string() + " " + (dir / "a.ply").string() +
                      " --samples 2000 --iou-resolution 16 --render-resolution 32 --json " + (dir / "m.json").string(),
                  dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("volume IoU:     1.0000"), std::string::npos) << r.output;
  std::ifstream f(dir / "m.json");
  nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_DOUBLE_EQ(j["volume_iou"]["iou"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["appearance"]["ssim"].get<double>(), 1.0);
  EXPECT_EQ(j["volume_iou"]["resolution"].get<int>(), 16);
  for (const auto& e : fs::directory_iterator(dir))  // no temporary left behind
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

// The first mesh is the prediction, the second the ground truth. GT: a unit cube A and a box B of a
// quarter of its area (1.5 against 6) 1 unit away; prediction: A alone. Every predicted sample lies on
// the GT (precision 1, accuracy 0); a fifth of the GT's samples lie on B (recall 0.8), at 1.25 units from
// A on average: completeness 0.2 x 1.25 x 0.4 (the GT's 2.5-unit extent scaled to 1) = 0.1. Swapped
// arguments swap both pairs.
TEST_F(CliEval, ArgumentsArePredictionThenGroundTruth) {
  const Mesh a = test::box_mesh({0, 0, 0}, {1, 1, 1});
  Mesh gt = a;
  const Mesh b = test::box_mesh({2, 0, 0}, {2.5f, 0.5f, 0.5f});
  for (const Vec3i& f : b.faces) gt.faces.push_back(f + Vec3i::Constant(int(a.positions.size())));
  gt.positions.insert(gt.positions.end(), b.positions.begin(), b.positions.end());
  write_mesh(a, dir / "pred.ply");
  write_mesh(gt, dir / "gt.ply");
  CliRun r = run_cli("eval " + (dir / "pred.ply").string() + " " + (dir / "gt.ply").string() +
                         " --given-frame --samples 20000 --no-appearance --iou-resolution 16 --json " +
                         (dir / "m.json").string(),
                     dir);
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream f(dir / "m.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["frame"], "shared");
  EXPECT_LT(j["chamfer"]["accuracy"].get<double>(), 1e-5);
  EXPECT_NEAR(j["chamfer"]["completeness"].get<double>(), 0.1, 0.005);  // 20000 samples: about 0.001 either way
  for (const auto& score : j["fscore"]) {
    EXPECT_DOUBLE_EQ(score["precision"].get<double>(), 1.0) << score;
    EXPECT_NEAR(score["recall"].get<double>(), 0.8, 0.015) << score;  // 20000 samples: standard error 0.003
  }
}

// --views: the prediction against the masks it came from. A box with a band 5 px above it (64 px views of
// the box alone): the band's pixels in every view, two pieces against the hull's one.
TEST_F(CliEval, ViewsGiveTheAgreementWithTheInputMasks) {
  const Vec3f lo = Vec3f::Constant(-0.5f), hi = Vec3f::Constant(0.5f);
  u3d::testing::write_view_set(u3d::testing::boxes_views({{lo, hi}}, 64), dir / "views");
  Mesh pred = test::box_mesh(lo, hi);
  const Mesh band = test::box_mesh(Vec3f(-0.25f, 0.625f, -0.03125f), Vec3f(0.25f, 0.6875f, 0.03125f));
  for (const Vec3i& f : band.faces) pred.faces.push_back(f + Vec3i::Constant(int(pred.positions.size())));
  pred.positions.insert(pred.positions.end(), band.positions.begin(), band.positions.end());
  write_mesh(pred, dir / "pred.ply");
  const std::string meshes = (dir / "pred.ply").string() + " " + (dir / "pred.ply").string();
  CliRun r = run_cli("eval " + meshes + " --samples 2000 --iou-resolution 16 --no-appearance --views " +
                         (dir / "views").string() + " --json " + (dir / "m.json").string(),
                     dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("front 32 px in 1 blob(s), largest 32, right 4 px"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("components:     mesh 2, visual hull of the masks 1"), std::string::npos) << r.output;
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "m.json"));
  EXPECT_EQ(j["mask_agreement"]["views"][2]["spurious"]["largest_blob"].get<int>(), 32);
  EXPECT_EQ(j["mask_agreement"]["views"][2]["missing"]["pixels"].get<int>(), 0);
  CliRun without = run_cli("eval " + meshes + " --samples 2000 --iou-resolution 16 --no-appearance --json " +
                               (dir / "m.json").string(),
                           dir);
  ASSERT_EQ(without.status, 0) << without.output;
  EXPECT_TRUE(nlohmann::json::parse(std::ifstream(dir / "m.json"))["mask_agreement"].is_null());
  EXPECT_TRUE(nlohmann::json::parse(std::ifstream(dir / "m.json"))["input_view_psnr"].is_null());
  // With appearance, the PSNR in the input views: the colourless mesh renders mid-gray 0.5 over every
  // pixel of the masks (the band lies off them), the views' gray is 128/255 in their 8-bit files.
  CliRun psnr = run_cli("eval " + meshes + " --samples 2000 --iou-resolution 16 --render-resolution 32 --views " +
                            (dir / "views").string() + " --json " + (dir / "m.json").string(),
                        dir);
  ASSERT_EQ(psnr.status, 0) << psnr.output;
  EXPECT_NE(psnr.output.find("input views:    PSNR 54.151 dB"), std::string::npos) << psnr.output;
  j = nlohmann::json::parse(std::ifstream(dir / "m.json"));
  EXPECT_NEAR(j["input_view_psnr"]["psnr"].get<double>(), 20 * std::log10(510.0), 1e-3);
  EXPECT_EQ(j["input_view_psnr"]["ssaa"].get<int>(), 2);
  EXPECT_EQ(j["input_view_psnr"]["views"][1]["pixels"].get<int>(), 32 * 32);
}

// A grid of 10^9 cells (--iou-resolution 1024) runs for minutes: the user is told before it starts.
TEST_F(CliEval, LargeIouGridsAreAnnounced) {
  std::ofstream(dir / "empty.obj") << "# no geometry\n";
  const std::string meshes = (dir / "empty.obj").string() + " " + (dir / "empty.obj").string();
  CliRun large = run_cli("eval " + meshes + " --iou-resolution 1024", dir, /*quiet=*/false);
  EXPECT_NE(large.output.find("note: --iou-resolution 1024 classifies 1073741824 grid cells"), std::string::npos)
      << large.output;
  CliRun small = run_cli("eval " + meshes + " --iou-resolution 64", dir, /*quiet=*/false);
  EXPECT_EQ(small.output.find("note:"), std::string::npos) << small.output;
}

TEST_F(CliEval, EmptyOrMissingMeshesFailWithAMessage) {
  std::ofstream(dir / "empty.obj") << "# no geometry\n";
  write_mesh(test::box_mesh({0, 0, 0}, {1, 1, 1}), dir / "box.obj");
  CliRun empty = run_cli("eval " + (dir / "empty.obj").string() + " " + (dir / "box.obj").string(), dir);
  EXPECT_EQ(empty.status, 1) << empty.output;
  EXPECT_NE(empty.output.find("unique3d: error:"), std::string::npos) << empty.output;
  EXPECT_NE(empty.output.find("empty.obj"), std::string::npos) << empty.output;
  CliRun missing = run_cli("eval " + (dir / "nope.obj").string() + " " + (dir / "box.obj").string(), dir);
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("nope.obj"), std::string::npos) << missing.output;
}

// As the library test (tests/eval/test_view_perturbation.cpp): the right view (camera on +X) rolled 90
// degrees counter-clockwise turns an upward normal toward +Z, the picture's left; the other views
// and files are copied, and the record says what was done.
TEST_F(CliEval, PerturbRollsTheNamedViewWithItsNormals) {
  fs::create_directories(dir / "views");
  Image up(9, 9, 4, 1.f), toward_x(9, 9, 4, 1.f);
  for (size_t p = 0; p < up.pixel_count(); ++p) {
    up.data[p * 4 + 0] = up.data[p * 4 + 2] = 0.5f;              // (0, 1, 0)
    toward_x.data[p * 4 + 1] = toward_x.data[p * 4 + 2] = 0.5f;  // (1, 0, 0)
  }
  save_image(up, dir / "views" / "right_normal.png", 16);
  save_image(toward_x, dir / "views" / "front_normal.png", 16);
  save_image(Image(9, 9, 4, 1.f), dir / "views" / "front_rgb.png");
  std::ofstream(dir / "views" / "notes.txt") << "kept";
  CliRun r = run_cli(
      "perturb " + (dir / "views").string() + " -o " + (dir / "out").string() + " --rotate-view right:90 --seed 1",
      dir);
  ASSERT_EQ(r.status, 0) << r.output;
  const auto normal_at_centre = [](const Image& image) {
    const float* p = image.pixel(4, 4);
    return Vec3f(2 * p[0] - 1, 2 * p[1] - 1, 2 * p[2] - 1);
  };
  const Vec3f right = normal_at_centre(load_image_rgba(dir / "out" / "right_normal.png"));
  EXPECT_TRUE(right.isApprox(Vec3f(0, 0, 1), 1e-3f)) << right.transpose();
  const Vec3f front = normal_at_centre(load_image_rgba(dir / "out" / "front_normal.png"));
  EXPECT_TRUE(front.isApprox(Vec3f(1, 0, 0), 1e-3f)) << front.transpose();
  EXPECT_EQ(load_image_rgba(dir / "out" / "front_rgb.png").data, Image(9, 9, 4, 1.f).data);
  EXPECT_TRUE(fs::exists(dir / "out" / "notes.txt"));
  std::ifstream record(dir / "out" / "perturbation.json");
  const nlohmann::json j = nlohmann::json::parse(record);
  EXPECT_EQ(j["views"]["right"]["rotate_deg"].get<float>(), 90.f);
}

TEST_F(CliEval, PerturbRejectsBadViewSpecs) {
  fs::create_directories(dir / "views");
  CliRun bad_view = run_cli("perturb " + (dir / "views").string() + " -o " + (dir / "out").string() +
                             " --rotate-view top:3", dir);
  EXPECT_EQ(bad_view.status, 1);
  EXPECT_NE(bad_view.output.find("unknown view 'top'"), std::string::npos) << bad_view.output;
  CliRun bad_number = run_cli("perturb " + (dir / "views").string() + " -o " + (dir / "out").string() +
                               " --scale-view back:big", dir);
  EXPECT_EQ(bad_number.status, 1);
  EXPECT_NE(bad_number.output.find("not a number"), std::string::npos) << bad_number.output;
  CliRun bad_field = run_cli("perturb " + (dir / "views").string() + " -o " + (dir / "out").string() +
                              " --warp 2", dir);
  EXPECT_EQ(bad_field.status, 1);
  EXPECT_NE(bad_field.output.find("--warp expects AMPLITUDE_PX:SCALE_PX"), std::string::npos) << bad_field.output;
  CliRun bad_scale = run_cli("perturb " + (dir / "views").string() + " -o " + (dir / "out").string() +
                              " --bend 3:0", dir);
  EXPECT_EQ(bad_scale.status, 1);
  EXPECT_NE(bad_scale.output.find("--bend: the scale must be positive"), std::string::npos) << bad_scale.output;
}

// A bad file among the inputs fails the run before anything is written: no folder at -o, no early
// outputs; a symlink loop is named in an ordinary error.
TEST_F(CliEval, PerturbWritesNothingWhenAnInputIsBad) {
  fs::create_directories(dir / "views");
  save_image(Image(16, 16, 4, 1.f), dir / "views" / "front_rgb.png");
  save_image(Image(16, 16, 4, 1.f), dir / "views" / "front_normal.png");
  std::ofstream(dir / "views" / "left_normal.png") << "not a picture";
  CliRun corrupt = run_cli("perturb " + (dir / "views").string() + " -o " + (dir / "out").string(), dir);
  EXPECT_EQ(corrupt.status, 1) << corrupt.output;
  EXPECT_NE(corrupt.output.find("unique3d: error: "), std::string::npos) << corrupt.output;
  EXPECT_NE(corrupt.output.find("left_normal.png"), std::string::npos) << corrupt.output;
  EXPECT_FALSE(fs::exists(dir / "out"));

  fs::remove(dir / "views" / "left_normal.png");
  fs::create_symlink(dir / "views" / "left_normal.png", dir / "views" / "left_normal.png");
  CliRun loop = run_cli("perturb " + (dir / "views").string() + " -o " + (dir / "out").string(), dir);
  EXPECT_EQ(loop.status, 1) << loop.output;
  EXPECT_NE(loop.output.find("unique3d: error: "), std::string::npos) << loop.output;
  EXPECT_NE(loop.output.find("Too many levels of symbolic links"), std::string::npos) << loop.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// Option errors found by the parser (a missing argument, a path that is a symlink loop) take the same
// form as every other error.
TEST_F(CliEval, ParserErrorsArePrefixedAndExitWithOne) {
  fs::create_symlink(dir / "loop.obj", dir / "loop.obj");
  CliRun loop = run_cli("eval " + (dir / "loop.obj").string() + " " + (dir / "loop.obj").string(), dir);
  EXPECT_EQ(loop.status, 1) << loop.output;
  EXPECT_EQ(loop.output.rfind("unique3d: error: ", 0), 0u) << loop.output;
  EXPECT_NE(loop.output.find("loop.obj"), std::string::npos) << loop.output;
  CliRun missing = run_cli("eval", dir);
  EXPECT_EQ(missing.status, 1) << missing.output;
  EXPECT_EQ(missing.output.rfind("unique3d: error: ", 0), 0u) << missing.output;
  CliRun help = run_cli("eval --help", dir);
  EXPECT_EQ(help.status, 0) << help.output;
}
