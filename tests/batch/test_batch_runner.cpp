// One shard's run: each object's folder appears whole (mesh, previews, done.json) or not at all; a re-run
// skips what is done and redoes what changed; a failure is recorded and the batch goes on; photos run
// the whole method (on the tiny stand-in networks) with the model folder's checks in done.json.
#include "batch/batch_runner.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "batch/content_hash.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/synthetic_views.h"
#include "io/io_test_util.h"
#include "pipeline/tiny_model_folder.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(test::read_file(path)); }

// Small and quick: a sphere at 64 px, a few optimisation steps.
BatchSpec small_spec(const fs::path& out) {
  BatchSpec spec;
  spec.output = out;
  ReconstructOptions& o = spec.reconstruct.options;
  o.coarse.steps = 10;
  o.refine.steps = 5;
  o.faces = 500;
  o.texture.atlas.texture_size = 128;
  o.silhouette_fit.enabled = false;
  spec.reconstruct_options = {{"--coarse-steps", "10"}};
  return spec;
}

std::vector<BatchInput> sphere_inputs(const fs::path& dir, std::initializer_list<std::pair<const char*, float>> spheres) {
  std::vector<BatchInput> inputs;
  for (const auto& [name, radius] : spheres) {
    testing::write_view_set(testing::sphere_views(radius, 64), dir / name);
    inputs.push_back({dir / name, name, BatchMode::Reconstruct});
  }
  return inputs;
}

std::vector<std::string> hidden_entries(const fs::path& out) {
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(out))
    if (e.path().filename().string().front() == '.') names.push_back(e.path().filename().string());
  return names;
}

class BatchRunner : public ::testing::Test {
 protected:
  void SetUp() override { set_progress_quiet(true); }
};

TEST(ContentHash, Sha256OfAFileMatchesTheStandardVector) {
  const fs::path dir = testing::fresh_temp_dir("batch_sha");
  std::ofstream(dir / "abc.txt") << "abc";
  // FIPS 180-2, appendix B.1.
  EXPECT_EQ(sha256_file(dir / "abc.txt"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_THROW(sha256_file(dir / "missing"), Error);
}

TEST_F(BatchRunner, EachObjectGetsAWholeFolderAndARerunSkipsIt) {
  const fs::path dir = testing::fresh_temp_dir("batch_run");
  const std::vector<BatchInput> inputs = sphere_inputs(dir / "in", {{"small", 0.5f}, {"large", 0.7f}});
  const BatchSpec spec = small_spec(dir / "out");
  const BatchReport first = run_batch(inputs, spec);
  ASSERT_EQ(first.count(ObjectOutcome::Done), 2u) << batch_report_json(first).dump(2);
  EXPECT_GT(first.peak_memory_mib(), 0.0);
  for (const BatchInput& input : inputs) {
    const fs::path folder = dir / "out" / input.name;
    for (const char* file : {"mesh.glb", "mesh_views.png", "mesh_turntable.png", "done.json"})
      EXPECT_TRUE(fs::is_regular_file(folder / file)) << folder / file;
    const nlohmann::json done = read_json(folder / "done.json");
    EXPECT_EQ(done["name"], input.name);
    EXPECT_EQ(done["mode"], "reconstruct");
    EXPECT_EQ(done["input"]["sha256"], input_hash(input));
    EXPECT_EQ(done["input"]["path"], fs::absolute(input.path).lexically_normal().string());
    EXPECT_EQ(done["options"], spec.reconstruct_options);
    EXPECT_FALSE(done["program"]["version"].get<std::string>().empty());
    EXPECT_GT(done["peak_memory_mib"].get<double>(), 0.0);
    EXPECT_GE(done["stages"].size(), 4u);
    EXPECT_EQ(done["files"], nlohmann::json({"done.json", "mesh.glb", "mesh_turntable.png", "mesh_views.png"}));
  }
  EXPECT_TRUE(hidden_entries(dir / "out").empty());

  const std::string done_before = test::read_file(dir / "out" / "small" / "done.json");
  const BatchReport second = run_batch(inputs, spec);
  EXPECT_EQ(second.count(ObjectOutcome::Skipped), 2u);
  EXPECT_EQ(test::read_file(dir / "out" / "small" / "done.json"), done_before);
}

TEST_F(BatchRunner, ChangedInputsAndOptionsAreRedone) {
  const fs::path dir = testing::fresh_temp_dir("batch_stale");
  const std::vector<BatchInput> inputs = sphere_inputs(dir / "in", {{"a", 0.5f}, {"b", 0.6f}});
  BatchSpec spec = small_spec(dir / "out");
  ASSERT_EQ(run_batch(inputs, spec).count(ObjectOutcome::Done), 2u);
  const std::string glb_b = test::read_file(dir / "out" / "b" / "mesh.glb");

  // b's views now show a larger sphere: b is redone, a skipped.
  testing::write_view_set(testing::sphere_views(0.75f, 64), dir / "in" / "b");
  const BatchReport changed = run_batch(inputs, spec);
  EXPECT_EQ(changed.objects[0].outcome, ObjectOutcome::Skipped);
  EXPECT_EQ(changed.objects[1].outcome, ObjectOutcome::Done);
  EXPECT_NE(test::read_file(dir / "out" / "b" / "mesh.glb"), glb_b);
  EXPECT_EQ(read_json(dir / "out" / "b" / "done.json")["input"]["sha256"], input_hash(inputs[1]));

  // Other options: both redone, and the stale folders replaced without leftovers.
  spec.reconstruct_options = {{"--coarse-steps", "12"}};
  spec.reconstruct.options.coarse.steps = 12;
  EXPECT_EQ(run_batch(inputs, spec).count(ObjectOutcome::Done), 2u);
  EXPECT_EQ(read_json(dir / "out" / "a" / "done.json")["options"], spec.reconstruct_options);
  EXPECT_TRUE(hidden_entries(dir / "out").empty());
}

TEST_F(BatchRunner, AFailureIsRecordedAndTheBatchGoesOn) {
  const fs::path dir = testing::fresh_temp_dir("batch_fail");
  std::vector<BatchInput> inputs = sphere_inputs(dir / "in", {{"good", 0.5f}, {"broken", 0.5f}});
  std::ofstream(dir / "in" / "broken" / "left_normal.png", std::ios::trunc) << "not a png";
  std::sort(inputs.begin(), inputs.end(), [](const BatchInput& a, const BatchInput& b) { return a.name < b.name; });
  // A killed run's temporary folder of `good`.
  fs::create_directories(dir / "out" / ".good+partial-node7-1234");
  std::ofstream(dir / "out" / ".good+partial-node7-1234" / "mesh.glb") << "half";
  const BatchSpec spec = small_spec(dir / "out");
  const BatchReport report = run_batch(inputs, spec);
  ASSERT_EQ(report.objects.size(), 2u);
  EXPECT_EQ(report.objects[0].input.name, "broken");
  EXPECT_EQ(report.objects[0].outcome, ObjectOutcome::Failed);
  EXPECT_NE(report.objects[0].error.find("left_normal.png"), std::string::npos) << report.objects[0].error;
  EXPECT_EQ(report.objects[1].outcome, ObjectOutcome::Done);
  EXPECT_FALSE(fs::exists(dir / "out" / "broken"));
  const nlohmann::json failed = read_json(dir / "out" / "broken.failed.json");
  EXPECT_EQ(failed["error"], report.objects[0].error);
  EXPECT_EQ(failed["name"], "broken");
  EXPECT_TRUE(hidden_entries(dir / "out").empty());

  // Repaired, the next run does it and drops the failure file.
  testing::write_view_set(testing::sphere_views(0.5f, 64), dir / "in" / "broken");
  const BatchReport again = run_batch(inputs, spec);
  EXPECT_EQ(again.objects[0].outcome, ObjectOutcome::Done);
  EXPECT_EQ(again.objects[1].outcome, ObjectOutcome::Skipped);
  EXPECT_FALSE(fs::exists(dir / "out" / "broken.failed.json"));
}

TEST_F(BatchRunner, CancelledLeavesNoPartialFolder) {
  struct CancelAtTheCoarseStage : ProgressListener {
    void on_event(const ProgressEvent& e) override {
      if (e.kind == ProgressEvent::Kind::StageBegin && e.text == "coarse") cancel = true;
    }
    bool cancel_requested() override { return cancel; }
    bool cancel = false;
  } listener;
  const fs::path dir = testing::fresh_temp_dir("batch_cancel");
  const std::vector<BatchInput> inputs = sphere_inputs(dir / "in", {{"a", 0.5f}});
  EXPECT_THROW(run_batch(inputs, small_spec(dir / "out"), &listener), Cancelled);
  EXPECT_TRUE(fs::is_empty(dir / "out"));
}

TEST_F(BatchRunner, PhotosNeedTheModelFolderBeforeAnyWork) {
  const fs::path dir = testing::fresh_temp_dir("batch_no_models");
  testing::write_disk_photo(dir / "photo.png");
  try {
    run_batch({{dir / "photo.png", "photo", BatchMode::Generate}}, small_spec(dir / "out"));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--models"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST_F(BatchRunner, PhotosRunTheWholeMethodWithTheModelChecksRecorded) {
  const fs::path dir = testing::fresh_temp_dir("batch_photos");
  testing::write_tiny_model_folder(dir / "models");
  fs::create_directories(dir / "in");
  testing::write_disk_photo(dir / "in" / "disk.png");
  testing::write_disk_photo(dir / "in" / "disk2.png");
  BatchSpec spec = small_spec(dir / "out");
  spec.generate.network.models = dir / "models";
  spec.generate.network.precision = nn::Precision::kFp32;
  testing::use_tiny_sizes(spec.generate);
  const bool room = available_memory_mib() > kStageWorkMiB + 1024.0;  // the tiny networks are a few MiB
  const BatchReport report = run_batch({{dir / "in" / "disk.png", "disk", BatchMode::Generate},
                                        {dir / "in" / "disk2.png", "disk2", BatchMode::Generate}},
                                       spec);
  ASSERT_EQ(report.count(ObjectOutcome::Done), 2u) << batch_report_json(report).dump(2);
  // The networks are read for the first photo (it has transparency: no background removal) and kept for
  // the second where memory allows.
  EXPECT_EQ(report.objects[0].networks_loaded, 5u);  // upscaler, multi-view, refinement's two halves, normals
  EXPECT_EQ(report.objects[1].networks_loaded, room ? 0u : 5u);
  // Kept networks draw what fresh ones do: the same mesh for the same photo, and the same as a plain
  // generate, whose stages load and free their networks.
  const std::string mesh = test::read_file(dir / "out" / "disk" / "mesh.glb");
  EXPECT_TRUE(mesh == test::read_file(dir / "out" / "disk2" / "mesh.glb"));
  GenerateRequest plain = spec.generate;
  plain.image = dir / "in" / "disk.png";
  plain.output = dir / "plain.glb";
  generate(plain);
  EXPECT_TRUE(mesh == test::read_file(dir / "plain.glb"));
  const nlohmann::json done = read_json(dir / "out" / "disk" / "done.json");
  EXPECT_EQ(done["mode"], "generate");
  EXPECT_EQ(done["input"]["sha256"], sha256_file(dir / "in" / "disk.png"));
  EXPECT_EQ(done["models"]["checks"].size(), 4u);  // upscaler, multi-view, normals, refinement
  std::vector<std::string> stages;
  for (const nlohmann::json& s : done["stages"]) {
    stages.push_back(s["name"]);
    EXPECT_GT(s["peak_memory_mib"].get<double>(), 0.0) << s.dump();
  }
  EXPECT_EQ(stages, generate_stage_names());
  for (const char* file : {"mesh.glb", "mesh_views.png", "mesh_turntable.png"})
    EXPECT_TRUE(fs::is_regular_file(dir / "out" / "disk" / file)) << file;
}

}  // namespace
}  // namespace u3d
