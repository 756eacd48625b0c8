// The refinement stage loaded from folders in the official layouts (Stable Diffusion 1.5 base, Unique3D's
// ckpt/controlnet-tile, h94/IP-Adapter), made of tiny models: the golden UNet, VAE, CLIP image encoder
// and IP-Adapter, plus a seeded random text encoder (the tokenizer's full vocabulary, 16 wide to fit the
// UNet) and ControlNet (one conditioning downsampling to fit the tiny VAE). It runs end to end.
#include "nn/pipelines/unique3d_refine.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>

#include "golden.h"
#include "refine_folders.h"
#include "nn/checkpoint/safetensors.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;
namespace fs = std::filesystem;

class CountingNoise : public NoiseSource {
 public:
  torch::Tensor randn(at::IntArrayRef shape, torch::ScalarType dtype) override {
    ++draws;
    return seeded.randn(shape, dtype);
  }
  SeededNoise seeded{233};
  int draws = 0;
};

class RefineFolders : public ::testing::Test {
 protected:
  void SetUp() override {
    root = fs::temp_directory_path() / ("u3d_test_refine_" + std::to_string(::getpid()));
    fs::remove_all(root);
    paths = {root / "stable-diffusion-v1-5", root / "ckpt", root / "IP-Adapter"};

    write_tiny_refine_folders(paths);
  }
  void TearDown() override { fs::remove_all(root); }

  fs::path root;
  RefineCheckpoints paths;
};

TEST_F(RefineFolders, RunsTheImg2ImgTailEndToEnd) {
  auto encoders = RefineEncoders::load(paths, Precision::kFp32);
  auto model = RefineModel::load(paths, Precision::kFp32);
  std::vector<torch::Tensor> views;
  for (int i = 0; i < 4; ++i) views.push_back(torch::randint(0, 256, {20, 20, 3}, torch::kUInt8));
  const torch::Tensor front = torch::randint(0, 256, {40, 30, 3}, torch::kUInt8);
  RefineSettings settings;
  settings.size = 32;
  settings.steps = 10;  // strength 0.2: the last 2 of 10 steps run
  CountingNoise noise;
  TensorMap trace;
  const torch::Tensor out = model->run(encoders->encode(views, front, settings, &trace), settings, noise, &trace);

  EXPECT_EQ(out.sizes(), (std::vector<int64_t>{4, 16, 16, 3}));
  EXPECT_TRUE(torch::isfinite(out).all().item<bool>());
  EXPECT_GE(out.min().item<float>(), 0.0f);
  EXPECT_LE(out.max().item<float>(), 1.0f);
  // VAE sample, img2img noise, one draw per step.
  EXPECT_EQ(noise.draws, 4);
  EXPECT_TRUE(torch::equal(trace.at("timesteps"), model->scheduler->timesteps().narrow(0, 8, 2)));
  EXPECT_EQ(trace.at("grid").sizes(), (std::vector<int64_t>{40, 40, 3}));
  EXPECT_TRUE(torch::equal(trace.at("grid").narrow(0, 20, 20).narrow(1, 0, 20), views[2]));
  EXPECT_EQ(trace.at("prompt_embeds").sizes(), (std::vector<int64_t>{2, 77, 16}));
  // The unconditional image embedding is zeros, the conditional one the front image's.
  EXPECT_EQ(trace.at("image_embeds")[0].abs().max().item<float>(), 0.0f);
  EXPECT_GT(trace.at("image_embeds")[1].abs().max().item<float>(), 0.0f);
  // The quarters are the decoded grid in grid order.
  EXPECT_TRUE(torch::equal(out[3], trace.at("images").narrow(0, 16, 16).narrow(1, 16, 16)));
}

// The refinement stage frees the UNet, IP-Adapter and ControlNet before decoding the grid: the views
// are the same, and the spent model names the reason when asked to run again.
TEST_F(RefineFolders, FreeingTheNetworksAsDoneKeepsTheViews) {
  auto encoders = RefineEncoders::load(paths, Precision::kFp32);
  auto model = RefineModel::load(paths, Precision::kFp32);
  std::vector<torch::Tensor> views;
  for (int i = 0; i < 4; ++i) views.push_back(torch::randint(0, 256, {16, 16, 3}, torch::kUInt8));
  RefineSettings settings;
  settings.size = 32;
  settings.steps = 10;
  const RefineConditioning kept_conditioning = encoders->encode(views, views[0], settings);
  SeededNoise kept_noise(5), freed_noise(5);
  const torch::Tensor kept = model->run(kept_conditioning, settings, kept_noise);
  settings.free_networks_as_done = true;
  const RefineConditioning conditioning = encoders->encode(views, views[0], settings);
  EXPECT_TRUE(encoders->text_encoder.is_empty());
  EXPECT_TRUE(encoders->vae.is_empty());
  EXPECT_TRUE(torch::equal(kept_conditioning.grid.mean, conditioning.grid.mean));
  const torch::Tensor freed = model->run(conditioning, settings, freed_noise);
  EXPECT_TRUE(torch::equal(kept, freed));
  EXPECT_TRUE(model->unet.is_empty());
  EXPECT_TRUE(model->controlnet.is_empty());
  for (int half = 0; half < 2; ++half) {
    try {
      if (half == 0) encoders->encode(views, views[0], settings);
      else model->run(conditioning, settings, freed_noise);
      ADD_FAILURE() << "no error from half " << half;
    } catch (const u3d::Error& e) {
      EXPECT_NE(std::string(e.what()).find("freed"), std::string::npos) << e.what();
    }
  }
}

TEST_F(RefineFolders, ListsTheFilesItReads) {
  const auto files = RefineModel::files(paths);
  EXPECT_EQ(files.size(), 14u);
  for (const auto& f : files) EXPECT_TRUE(fs::is_regular_file(f)) << f;
  EXPECT_EQ(files.back(), paths.ip_adapter / "models" / "ip-adapter_sd15.safetensors");
}

TEST_F(RefineFolders, MissingFilesAreNamed) {
  // Each half checks every file of both before reading any weights.
  auto expect_named = [&](const std::string& file, const std::string& source) {
    for (int half = 0; half < 2; ++half) {
      try {
        if (half == 0) RefineEncoders::load(paths, Precision::kFp32);
        else RefineModel::load(paths, Precision::kFp32);
        ADD_FAILURE() << "no error for the missing " << file << " (half " << half << ")";
      } catch (const u3d::Error& e) {
        EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(source), std::string::npos) << e.what();
      }
    }
  };
  fs::remove(paths.ip_adapter / "models" / "ip-adapter_sd15.safetensors");
  EXPECT_THROW(RefineModel::files(paths), u3d::Error);
  expect_named("ip-adapter_sd15.safetensors", "h94/IP-Adapter");
  fs::remove_all(paths.ckpt / "controlnet-tile");
  expect_named("controlnet-tile", "space Wuvin/Unique3D");
}

TEST_F(RefineFolders, RejectsBadInputs) {
  auto encoders = RefineEncoders::load(paths, Precision::kFp32);
  auto model = RefineModel::load(paths, Precision::kFp32);
  CountingNoise noise;
  std::vector<torch::Tensor> views(3, torch::zeros({20, 20, 3}, torch::kUInt8));
  RefineSettings settings;
  settings.size = 32;
  const torch::Tensor front = torch::zeros({20, 20, 3}, torch::kUInt8);
  EXPECT_THROW(encoders->encode(views, front, settings), u3d::Error);  // three views
  views.push_back(torch::zeros({20, 20, 3}, torch::kUInt8));
  EXPECT_THROW(encoders->encode(views, torch::zeros({20, 20, 4}, torch::kUInt8), settings), u3d::Error);
  std::vector<torch::Tensor> mixed = views;
  mixed[1] = torch::zeros({22, 22, 3}, torch::kUInt8);
  EXPECT_THROW(encoders->encode(mixed, front, settings), u3d::Error);
  settings.size = 30;
  EXPECT_THROW(encoders->encode(views, front, settings), u3d::Error);
  settings.size = 32;
  const RefineConditioning conditioning = encoders->encode(views, front, settings);
  settings.steps = 4;  // 4 x 0.2 rounds down to no step
  EXPECT_THROW(model->run(conditioning, settings, noise), u3d::Error);
  settings.steps = 50;
  settings.size = 48;  // not the size the conditioning was made at
  EXPECT_THROW(model->run(conditioning, settings, noise), u3d::Error);
  settings.size = 32;
  settings.guidance_scale = 1.0;  // the conditioning was made with guidance: two halves, not one
  EXPECT_THROW(model->run(conditioning, settings, noise), u3d::Error);
  EXPECT_EQ(noise.draws, 0);
}

}  // namespace
}  // namespace u3d::nn
