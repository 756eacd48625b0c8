// `unique3d generate` and the diffusion stages' own commands (`multiview`, `refine`, `normals`) on the
// tiny models at small sizes. Every option is given a value other than its default, and the command's
// files must equal the library's for the same request byte for byte, so an option that does not reach the
// library fails; --json states every stage; the front view's mask is the photo's subject; resuming with
// --official-scale rescales the same mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/image.h"
#include "core/synthetic_views.h"
#include "io/io_test_util.h"
#include "io/mesh_io.h"
#include "nn/runtime.h"
#include "pipeline/generate.h"
#include "pipeline/image_stages.h"
#include "pipeline/multiview_stage.h"
#include "pipeline/normal_stage.h"
#include "pipeline/tiny_model_folder.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int status = -1;
  std::string output;  // stdout and stderr
};

CliRun run_cli(const std::string& args, const fs::path& log) {
  CliRun r;
  r.status = std::system((std::string(UNIQUE3D_CLI) + " " + args + " > " + log.string() + " 2>&1").c_str());
  r.output = test::read_file(log);
  return r;
}

// The four views of a stage folder, byte for byte.
void expect_same_views(const fs::path& cli, const fs::path& library, bool normals) {
  for (View v : kAllViews)
    for (bool normal : {false, true}) {
      if (normal && !normals) continue;
      const std::string name = view_file_name(v, normal);
      ASSERT_TRUE(fs::exists(cli / name)) << cli / name;
      EXPECT_TRUE(test::read_file(cli / name) == test::read_file(library / name)) << name;
    }
}

// The command's run-time set-up (cli/main.cpp: libtorch's AVX-512 kernels where the CPU has them, the
// threads) in this process as well, before any network runs in it, so that the library's numbers here are
// the command's bit for bit.
struct CommandRuntime : ::testing::Environment {
  void SetUp() override { nn::configure_torch_threads(); }
};
::testing::Environment* const command_runtime = ::testing::AddGlobalTestEnvironment(new CommandRuntime);

class GenerateCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    set_progress_quiet(true);
    dir = new fs::path(testing::fresh_temp_dir("cli_generate"));
    testing::write_tiny_model_folder(*dir / "models");
    testing::write_disk_photo(*dir / "photo.png");
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir);
    delete dir;
  }
  static std::string models() { return " --models " + (*dir / "models").string() + " --dtype fp32 --seed 5"; }
  static NetworkOptions network() {
    NetworkOptions n;
    n.models = *dir / "models";
    n.precision = nn::Precision::kFp32;
    n.seed = 5;
    return n;
  }
  static fs::path* dir;
};
fs::path* GenerateCommand::dir = nullptr;

TEST_F(GenerateCommand, WritesTheLibrarysMeshAndSaysEachStage) {
  const fs::path d = *dir / "generate";
  fs::create_directories(d);
  // Small sizes and few steps (testing::use_tiny_sizes), no refinement, a coarse mesh and texture.
  const std::string small =
      " --steps 2 --no-refine --multiview-size 32 --refine-size 64 --normal-size 32 --coarse-steps 5 --refine-steps 5"
      " --no-silhouette-fit --faces 500 --texture-size 128";
  const CliRun r = run_cli("generate " + (*dir / "photo.png").string() + " -o " + (d / "cli.glb").string() +
                               models() + small + " --keep-intermediates " + (d / "kept").string() + " --json " +
                               (d / "summary.json").string(),
                           d / "generate.log");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("stages (fp32):"), std::string::npos) << r.output;

  // The front view's mask is the photo's disk, cropped to it and centred as the official preparation does
  // (no margin: nn/pipelines/input_photo.h): round (its area near pi/4 of its square box; the tiny random
  // upscaler frays the edge), centred, and the view's width.
  const Image front = load_image(d / "kept" / "front.png");
  ASSERT_EQ(front.channels, 4);
  int x0 = front.width, x1 = -1, y0 = front.height, y1 = -1;
  double area = 0.0, cx = 0.0, cy = 0.0;
  for (int y = 0; y < front.height; ++y)
    for (int x = 0; x < front.width; ++x)
      if (front.at(x, y, 3) > 0.5f) {
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        area += 1.0, cx += x, cy += y;
      }
  ASSERT_GT(area, 0.0);
  const double w = x1 - x0 + 1, h = y1 - y0 + 1;
  EXPECT_NEAR(w / h, 1.0, 0.05) << w << " x " << h;
  EXPECT_NEAR(area / (w * h), 3.14159265 / 4, 0.07);
  EXPECT_NEAR(cx / area, (front.width - 1) / 2.0, 0.02 * front.width);
  EXPECT_NEAR(cy / area, (front.height - 1) / 2.0, 0.02 * front.height);
  EXPECT_GT(w, 0.9 * front.width);

  GenerateRequest request;
  request.image = *dir / "photo.png";
  request.output = d / "library.glb";
  request.network = network();
  testing::use_tiny_sizes(request);
  request.refine = false;
  const GenerateSummary library = generate(request);
  EXPECT_TRUE(test::read_file(d / "cli.glb") == test::read_file(d / "library.glb"));

  std::ifstream in(d / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary.at("precision"), "fp32");
  const auto& stages = summary.at("stages");
  ASSERT_EQ(stages.size(), generate_stage_names().size());
  for (size_t i = 0; i < stages.size(); ++i) {
    EXPECT_EQ(stages[i].at("name"), generate_stage_names()[i]);
    EXPECT_FALSE(stages[i].at("resumed").get<bool>());
    EXPECT_GE(stages[i].at("seconds").get<double>(), 0.0);
    EXPECT_GT(stages[i].at("peak_memory_mib").get<double>(), 0.0);
  }
  EXPECT_EQ(summary.at("mesh").at("faces").get<size_t>(), library.reconstruction.mesh.face_count());
  // The kept images (the photo, three stages' four views, the view set), then the mesh.
  EXPECT_EQ(summary.at("written").size(), 1 + 4 * 3 + 8 + library.written.size());
  EXPECT_EQ(summary.at("written").back().get<std::string>(), (d / "cli.glb").string());

  // Resumed from the kept view set with the official scale: no stage but ISOMER runs, and the mesh is
  // the same mesh at 0.675 of its size.
  const CliRun resumed = run_cli("generate -o " + (d / "scaled.glb").string() + models() + small +
                                     " --from-intermediates " + (d / "kept").string() + " --official-scale --json " +
                                     (d / "resumed.json").string(),
                                 d / "resumed.log");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  std::ifstream resumed_in(d / "resumed.json");
  const nlohmann::json resumed_summary = nlohmann::json::parse(resumed_in);
  for (const auto& stage : resumed_summary.at("stages"))
    EXPECT_EQ(stage.at("resumed").get<bool>(), stage.at("name") != "reconstruct") << stage.at("name");
  const Mesh original = read_mesh(d / "cli.glb"), scaled = read_mesh(d / "scaled.glb");
  ASSERT_EQ(original.positions.size(), scaled.positions.size());
  ASSERT_EQ(original.faces, scaled.faces);
  for (size_t i = 0; i < original.positions.size(); ++i)
    EXPECT_LT((scaled.positions[i] - kOfficialOutputScale * original.positions[i]).norm(), 1e-5f) << i;
}

TEST_F(GenerateCommand, StageCommandsWriteTheLibrarysViews) {
  const fs::path d = *dir / "stages";
  const std::string photo = (*dir / "photo.png").string();
  CliRun r = run_cli("multiview " + photo + " -o " + (d / "mv").string() + models() + " --size 32 --steps 2 --guidance 2",
                     d.parent_path() / "multiview.log");
  ASSERT_EQ(r.status, 0) << r.output;
  MultiViewRequest mv{photo, d / "mv_library", network(), {}};
  mv.options.size = 32;
  mv.options.steps = 2;
  mv.options.guidance_scale = 2.0;
  generate_views(mv);
  expect_same_views(d / "mv", d / "mv_library", false);

  r = run_cli("refine " + (d / "mv").string() + " --front " + photo + " -o " + (d / "refined").string() + models() +
                  " --size 64 --steps 10 --strength 0.3",
              d.parent_path() / "refine.log");
  ASSERT_EQ(r.status, 0) << r.output;
  RefineRequest refine{d / "mv", photo, d / "refined_library", network(), {}};
  refine.options.size = 64;
  refine.options.steps = 10;
  refine.options.strength = 0.3;
  refine_views(refine);
  expect_same_views(d / "refined", d / "refined_library", false);

  r = run_cli("normals " + (d / "refined").string() + " -o " + (d / "normals").string() + models() +
                  " --size 32 --steps 2 --guidance 2 --no-upscale",
              d.parent_path() / "normals.log");
  ASSERT_EQ(r.status, 0) << r.output;
  NormalRequest normals{d / "refined", std::nullopt, d / "normals_library", network(), {}};
  normals.options.size = 32;
  normals.options.steps = 2;
  normals.options.guidance_scale = 2.0;
  normals.options.upscale = false;
  predict_view_normals(normals);
  expect_same_views(d / "normals", d / "normals_library", true);
}

// The stage-by-stage recipe (README): `matte` and then `multiview` and `refine` on the cut-out give the
// views `generate` keeps, byte for byte, for a photo without transparency (its background removed by the
// tiny U^2-Net, its mask made solid) wider than 512 px (the preparation upscales none of it); `normals`
// prepares its --front photo the same way. --prepared takes generate's front.png as it is, for the same
// views again; without it, front.png is prepared again.
TEST_F(GenerateCommand, MatteThenMultiviewAndRefineGiveGeneratesViews) {
  const fs::path d = *dir / "recipe";
  fs::create_directories(d);
  Image photo(520, 500, 3, 0.55f);
  for (int y = 0; y < photo.height; ++y)
    for (int x = 0; x < photo.width; ++x)
      if ((x - 250) * (x - 250) + (y - 260) * (y - 260) < 180 * 180) {
        float* p = photo.pixel(x, y);
        p[0] = 0.9f, p[1] = 0.3f + 0.001f * y, p[2] = 0.2f;
      }
  save_image(photo, d / "photo.png");
  // generate's views (the command's are the library's: WritesTheLibrarysMeshAndSaysEachStage), the run
  // stopped where the upscaler would start, after the refined views are kept.
  struct CancelAtTheUpscaler : ProgressListener {
    bool reached = false;
    void on_event(const ProgressEvent& e) override {
      reached = reached || (e.kind == ProgressEvent::Kind::StageBegin && e.text == "loading the upscaler");
    }
    bool cancel_requested() override { return reached; }
  };
  GenerateRequest request;
  request.image = d / "photo.png";
  request.output = d / "mesh.glb";
  request.network = network();
  testing::use_tiny_sizes(request);
  request.keep_intermediates = d / "kept";
  CancelAtTheUpscaler cancel;
  EXPECT_THROW(generate(request, &cancel), Cancelled);
  ASSERT_TRUE(cancel.reached);

  CliRun r = run_cli("matte " + (d / "photo.png").string() + " -o " + (d / "object.png").string() + " --models " +
                  (*dir / "models").string() + " --dtype fp32",
              d / "matte.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const Image object = load_image(d / "object.png");
  ASSERT_EQ(object.channels, 4);
  float lo = 1.f, hi = 0.f;
  for (size_t i = 0; i < object.pixel_count(); ++i)
    lo = std::min(lo, object.data[4 * i + 3]), hi = std::max(hi, object.data[4 * i + 3]);
  EXPECT_LT(lo, 0.1f);  // a mask with a background, so that `multiview` does not remove it again
  EXPECT_GT(hi, 0.9f);

  r = run_cli("multiview " + (d / "object.png").string() + " -o " + (d / "mv").string() + models() +
                  " --size 32 --steps 2",
              d / "multiview.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_same_views(d / "mv", d / "kept" / "multiview", false);
  r = run_cli("refine " + (d / "mv").string() + " --front " + (d / "object.png").string() + " -o " +
                  (d / "refined").string() + models() + " --size 64 --steps 10",
              d / "refine.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_same_views(d / "refined", d / "kept" / "refined", false);

  r = run_cli("multiview " + (d / "kept" / "front.png").string() + " --prepared -o " + (d / "mv_prepared").string() +
                  models() + " --size 32 --steps 2",
              d / "prepared.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_same_views(d / "mv_prepared", d / "kept" / "multiview", false);
  r = run_cli("refine " + (d / "mv").string() + " --front " + (d / "kept" / "front.png").string() + " --prepared -o " +
                  (d / "refined_prepared").string() + models() + " --size 64 --steps 10",
              d / "refine_prepared.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_same_views(d / "refined_prepared", d / "kept" / "refined", false);
  // `normals --front` prepares the cut-out (not square: 520 x 500) as generate does: the front view of the
  // view set is generate's front image, and --prepared on that image gives the same view set.
  r = run_cli("normals " + (d / "refined").string() + " --front " + (d / "object.png").string() + " -o " +
                  (d / "views").string() + models() + " --size 32 --steps 2",
              d / "normals.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const Image front = load_image(d / "kept" / "front.png"), view = load_image(d / "views" / "front_rgb.png");
  EXPECT_EQ(view.data, front.data);
  r = run_cli("normals " + (d / "refined").string() + " --front " + (d / "kept" / "front.png").string() +
                  " --prepared -o " + (d / "views_prepared").string() + models() + " --size 32 --steps 2",
              d / "normals_prepared.log");
  ASSERT_EQ(r.status, 0) << r.output;
  expect_same_views(d / "views_prepared", d / "views", true);
  // A photo given as prepared must be one: square.
  r = run_cli("normals " + (d / "refined").string() + " --front " + (d / "object.png").string() + " --prepared -o " +
                  (d / "never").string() + models() + " --size 32 --steps 2",
              d / "normals_not_prepared.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("without --prepared the photo is prepared first"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(d / "never"));

  // Without --prepared, the prepared image is prepared again (cropped once more, its colours put on white
  // again): other views, which is why the flag is there.
  r = run_cli("multiview " + (d / "kept" / "front.png").string() + " -o " + (d / "mv_twice").string() + models() +
                  " --size 32 --steps 2",
              d / "twice.log");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(test::read_file(d / "mv_twice" / "front_rgb.png") == test::read_file(d / "kept" / "multiview" / "front_rgb.png"));
}

}  // namespace
}  // namespace u3d
