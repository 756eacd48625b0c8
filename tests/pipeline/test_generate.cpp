// `generate` end to end on the tiny golden models at a small size (every stage, refinement included): a
// mesh file and every stage's intermediates; resuming from each stage's intermediates gives the same mesh
// file; a cancelled run keeps its completed stages; the photo checks.
#include "pipeline/generate.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "core/synthetic_views.h"
#include "io/io_test_util.h"
#include "io/mesh_io.h"
#include "pipeline/tiny_model_folder.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

class Generate : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    set_progress_quiet(true);
    dir = new fs::path(testing::fresh_temp_dir("generate"));
    testing::write_tiny_model_folder(*dir / "models");
    testing::write_disk_photo(*dir / "photo.png");
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir);
    delete dir;
  }
  static GenerateRequest request(const std::string& output) {
    GenerateRequest r;
    r.image = *dir / "photo.png";
    r.output = *dir / output;
    r.network.models = *dir / "models";
    r.network.precision = nn::Precision::kFp32;
    testing::use_tiny_sizes(r);
    return r;
  }
  static fs::path* dir;
};
fs::path* Generate::dir = nullptr;

// Cancels at the first denoising step, the multi-view model's: only the prepare stage completes.
struct CancelAtDenoising : ProgressListener {
  int steps = 0;
  void on_event(const ProgressEvent& e) override {
    if (e.kind == ProgressEvent::Kind::Step && e.text == "denoise") ++steps;
  }
  bool cancel_requested() override { return steps > 0; }
};

TEST_F(Generate, WritesTheMeshAndEveryStagesIntermediatesAndResumesFromThem) {
  GenerateRequest r = request("mesh.glb");
  r.keep_intermediates = *dir / "kept";
  const GenerateSummary s = generate(r);
  ASSERT_TRUE(fs::exists(*dir / "mesh.glb"));
  EXPECT_GT(read_mesh(*dir / "mesh.glb").face_count(), 0u);
  ASSERT_EQ(s.stages.size(), generate_stage_names().size());
  for (const auto& stage : s.stages) EXPECT_FALSE(stage.resumed) << stage.name;
  // front.png is the prepare stage's image of the photo.
  NetworkStageSummary prepare;
  const Image prepared = run_prepare_stage(load_image(r.image), r.network, false, prepare);
  EXPECT_EQ(load_image(*dir / "kept" / "front.png").data, prepared.data);
  for (const char* folder : {"multiview", "refined", "upscaled", "views"})
    EXPECT_TRUE(fs::exists(*dir / "kept" / folder / "left_rgb.png")) << folder;
  EXPECT_TRUE(fs::exists(*dir / "kept" / "views" / "left_normal.png"));

  // Resume after each stage, the last network stage included (then only ISOMER runs): remove the later
  // stages' outputs, and only the stages after run. The run says where it resumes; the photo is the
  // folder's front.png, so none need be given.
  struct Messages : ProgressListener {
    std::vector<std::string> seen;
    void on_event(const ProgressEvent& e) override {
      if (e.kind == ProgressEvent::Kind::Message) seen.push_back(e.text);
    }
  };
  const std::vector<std::string> later = {"", "views", "upscaled", "refined", "multiview"};
  const std::vector<std::string> done = {"prepare, multiview, refine, upscale and normals are done",
                                         "prepare, multiview, refine and upscale are done",
                                         "prepare, multiview and refine are done", "prepare and multiview are done",
                                         "prepare is done"};
  for (size_t removed = 0; removed < later.size(); ++removed) {
    if (!later[removed].empty()) fs::remove_all(*dir / "kept" / later[removed]);
    GenerateRequest resume = request("resumed.glb");
    resume.from_intermediates = *dir / "kept";
    if (removed % 2 == 0) resume.image.clear();
    Messages messages;
    const GenerateSummary rs = generate(resume, &messages);
    ASSERT_FALSE(messages.seen.empty());
    EXPECT_NE(messages.seen.front().find("resuming from " + (*dir / "kept").string() + ", where " + done[removed]),
              std::string::npos)
        << messages.seen.front();
    EXPECT_EQ(messages.seen.front().find("is not read") != std::string::npos, removed % 2 == 1) << messages.seen.front();
    // Exactly the stages before the removed folder's come from the folder, and the mesh is the one the
    // uninterrupted run wrote, byte for byte.
    const size_t kept_stages = later.size() - removed;
    ASSERT_EQ(rs.stages.size(), generate_stage_names().size());
    for (size_t i = 0; i < rs.stages.size(); ++i) EXPECT_EQ(rs.stages[i].resumed, i < kept_stages) << rs.stages[i].name;
    EXPECT_TRUE(test::read_file(*dir / "resumed.glb") == test::read_file(*dir / "mesh.glb")) << "resumed after " << kept_stages;
    fs::remove(*dir / "resumed.glb");
  }
}

// Cancelled during the multi-view model's denoising: the run ends with Cancelled, writes no mesh and
// keeps the completed prepare stage, from which a later run resumes.
TEST_F(Generate, CancelledDuringDenoisingKeepsTheCompletedStages) {
  GenerateRequest r = request("cancelled.glb");
  r.keep_intermediates = *dir / "kept_cancelled";
  CancelAtDenoising cancel;
  EXPECT_THROW(generate(r, &cancel), Cancelled);
  EXPECT_EQ(cancel.steps, 1);
  EXPECT_FALSE(fs::exists(*dir / "cancelled.glb"));
  EXPECT_TRUE(fs::exists(*dir / "kept_cancelled" / "front.png"));
  EXPECT_FALSE(fs::exists(*dir / "kept_cancelled" / "multiview"));

  GenerateRequest resume = request("cancelled.glb");
  resume.image.clear();
  resume.from_intermediates = *dir / "kept_cancelled";
  const GenerateSummary s = generate(resume);
  EXPECT_TRUE(fs::exists(*dir / "cancelled.glb"));
  ASSERT_EQ(s.stages.size(), generate_stage_names().size());
  for (size_t i = 0; i < s.stages.size(); ++i) EXPECT_EQ(s.stages[i].resumed, i == 0) << s.stages[i].name;
}

TEST_F(Generate, NeedsAPhotoUnlessItResumes) {
  GenerateRequest r = request("no_photo.glb");
  r.image.clear();
  try {
    generate(r);
    ADD_FAILURE() << "ran without a photo";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no photo given"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(*dir / "no_photo.glb"));
}

TEST_F(Generate, Takes16BitPhotos) {
  // A 16-bit PNG is read at full precision and handed to the networks as 8-bit values: the same photo
  // in 16 bits gives the 8-bit photo's front image, from which every later stage starts.
  save_image(load_image(*dir / "photo.png"), *dir / "photo16.png", /*bit_depth=*/16);
  // The later stages are the same functions of that image (the resume test shows it), so the run stops
  // once the prepare stage has kept it.
  GenerateRequest r = request("from16.glb");
  r.image = *dir / "photo16.png";
  r.keep_intermediates = *dir / "kept16";
  CancelAtDenoising cancel;
  EXPECT_THROW(generate(r, &cancel), Cancelled);
  NetworkStageSummary prepare;
  const Image from_8_bits = run_prepare_stage(load_image(*dir / "photo.png"), r.network, false, prepare);
  EXPECT_EQ(load_image(*dir / "kept16" / "front.png").data, from_8_bits.data);
}

TEST_F(Generate, TakesGreyscalePhotos) {
  // One channel, no alpha: the grey is used as RGB and the background is removed as for any opaque photo.
  const Image rgba = load_image(*dir / "photo.png");
  Image grey(rgba.width, rgba.height, 1, 1.f);
  for (int y = 0; y < rgba.height; ++y)
    for (int x = 0; x < rgba.width; ++x)
      if (rgba.pixel(x, y)[3] > 0.f) grey.pixel(x, y)[0] = 0.3f;
  save_image(grey, *dir / "grey.png");
  // The prepare stage's image is the one later stages start from (as in the 16-bit test).
  GenerateRequest r = request("from_grey.glb");
  r.image = *dir / "grey.png";
  r.keep_intermediates = *dir / "kept_grey";
  CancelAtDenoising cancel;
  EXPECT_THROW(generate(r, &cancel), Cancelled);
  const Image front = load_image(*dir / "kept_grey" / "front.png");
  EXPECT_EQ(front.channels, 4);
  // The file's grey as an RGB photo without alpha gives the same image.
  const Image read = load_image(*dir / "grey.png");
  ASSERT_EQ(read.channels, 1);
  Image rgb(read.width, read.height, 3, 0.f);
  for (size_t i = 0; i < read.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) rgb.data[3 * i + c] = read.data[i];
  NetworkStageSummary prepare;
  EXPECT_EQ(front.data, run_prepare_stage(rgb, r.network, false, prepare).data);
}

TEST_F(Generate, BrokenCheckpointsAreNamedBeforeAnyStageRuns) {
  const fs::path models = *dir / "models_broken";
  fs::copy(*dir / "models", models, fs::copy_options::recursive);
  const auto expect_error = [&](const fs::path& named) {
    GenerateRequest r = request("never.glb");
    r.network.models = models;
    r.keep_intermediates = *dir / "kept_broken";
    try {
      generate(r);
      ADD_FAILURE() << "no error for a broken " << named;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(named.string()), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(*dir / "never.glb"));
    EXPECT_FALSE(fs::exists(*dir / "kept_broken" / "front.png")) << "a stage ran";
  };
  // The last stage's network, truncated (an interrupted download).
  const fs::path normal_unet = models / "image2normal" / "unet_state_dict.pth";
  fs::resize_file(normal_unet, fs::file_size(normal_unet) - 1000);
  expect_error(normal_unet);
  fs::copy_file(*dir / "models" / "image2normal" / "unet_state_dict.pth", normal_unet,
                fs::copy_options::overwrite_existing);
  // The ControlNet's file holding another network's weights.
  const fs::path controlnet = models / "controlnet-tile" / "diffusion_pytorch_model.safetensors";
  fs::copy_file(models / "stable-diffusion-v1-5" / "vae" / "diffusion_pytorch_model.safetensors", controlnet,
                fs::copy_options::overwrite_existing);
  expect_error(controlnet);
  fs::remove_all(models);
}

TEST_F(Generate, PhotosNoStageCanUseAreNamed) {
  const auto expect_error = [&](const fs::path& photo, const std::string& needle) {
    GenerateRequest r = request("never.glb");
    r.image = photo;
    try {
      generate(r);
      ADD_FAILURE() << "no error for " << photo;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(*dir / "never.glb"));
  };
  std::ofstream(*dir / "text.png") << "not an image";
  expect_error(*dir / "text.png", "text.png");
  save_image(Image(40, 80, 4, 1.f), *dir / "tiny.png");
  expect_error(*dir / "tiny.png", "too small");
  save_image(Image(9000, 64, 4, 1.f), *dir / "huge.png");
  expect_error(*dir / "huge.png", "larger than");
  save_image(Image(96, 96, 4, 0.f), *dir / "transparent.png");
  expect_error(*dir / "transparent.png", "fully transparent");
}

}  // namespace
}  // namespace u3d
