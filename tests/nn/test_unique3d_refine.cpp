// The refinement stage loaded from folders in the official layouts (Stable Diffusion 1.5 base, Unique3D's
// ckpt/controlnet-tile, h94/IP-Adapter), made of tiny models: the golden UNet, VAE, CLIP image encoder
// and IP-Adapter, plus a seeded random text encoder (the tokenizer's full vocabulary, 16 wide to fit the
// UNet) and ControlNet (one conditioning downsampling to fit the tiny VAE). It runs end to end and
// reproduces the official pipeline's trace (tests/data/nn/refine_trace).
#include "nn/pipelines/unique3d_refine.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <utility>

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

// Replays the reference run's Gaussian draws in diffusers' order: the VAE sample, the img2img noise, one
// per step (inputs noise.0..3 of tests/data/nn/refine_trace).
class TraceNoise : public NoiseSource {
 public:
  explicit TraceNoise(TensorMap inputs) : inputs_(std::move(inputs)) {}
  torch::Tensor randn(at::IntArrayRef shape, torch::ScalarType dtype) override {
    const std::string key = "noise." + std::to_string(draws++);
    if (!inputs_.count(key)) {  // more draws than the reference made: more steps than it ran
      ADD_FAILURE() << "draw " << draws << " of shape " << shape << ": the reference drew only 4";
      return torch::zeros(shape, dtype);
    }
    const torch::Tensor& n = inputs_.at(key);
    EXPECT_EQ(n.sizes(), shape) << key;
    return n.to(dtype);
  }
  int draws = 0;

 private:
  TensorMap inputs_;
};

// The sum and the sum of squares of each tensor of a weights file, in key order (make_trace.py's fingerprint).
void expect_fingerprint(const fs::path& file, const TensorMap& reference, const std::string& prefix) {
  const TensorMap weights = load_safetensors(file);
  const torch::Tensor sums = reference.at(prefix + ".sum"), squares = reference.at(prefix + ".sumsq");
  ASSERT_EQ(int64_t(weights.size()), sums.size(0)) << file;
  int64_t i = 0;
  for (const auto& [key, value] : weights) {
    const double sum = value.to(torch::kDouble).sum().item<double>();
    const double square = value.to(torch::kDouble).pow(2).sum().item<double>();
    EXPECT_NEAR(sum, sums[i].item<double>(), 1e-9 * (1 + std::abs(sum))) << file << " " << key;
    EXPECT_NEAR(square, squares[i].item<double>(), 1e-9 * (1 + square)) << file << " " << key;
    ++i;
  }
}

// The official refinement call (Unique3D's refine_rgb -> refine_lr_with_sd: diffusers 0.27.2
// StableDiffusionControlNetImg2ImgPipeline with the tile ControlNet and the IP-Adapter), run by
// tests/data/nn/refine_trace/make_trace.py on these very folders with its noise injected: 10 steps at
// strength 0.2 (the last 2 run), guidance 5, a 48 px grid of four 24 px views refined at 64 px. Every
// recorded stage must match: the conditioning, the start, the latents after each step and the images.
TEST_F(RefineFolders, ReproducesTheOfficialRefinementTrace) {
  const TensorMap in = golden_tensors("refine_trace", "inputs");
  const TensorMap ref = golden_tensors("refine_trace", "outputs");
  // The seeded text encoder and ControlNet that refine_folders.h writes are the ones the trace was made with.
  expect_fingerprint(paths.base / "text_encoder" / "model.safetensors", ref, "weights.text_encoder");
  expect_fingerprint(paths.ckpt / "controlnet-tile" / "diffusion_pytorch_model.safetensors", ref, "weights.controlnet");

  auto encoders = RefineEncoders::load(paths, Precision::kFp32);
  auto model = RefineModel::load(paths, Precision::kFp32);
  std::vector<torch::Tensor> views;
  for (int64_t i = 0; i < 4; ++i) views.push_back(in.at("views")[i].contiguous());
  RefineSettings settings;  // the official strength, guidance, scales and prompts
  settings.size = 64;
  settings.steps = 10;
  TraceNoise noise(in);
  TensorMap trace;
  const torch::Tensor out = model->run(encoders->encode(views, in.at("front"), settings, &trace), settings, noise, &trace);
  EXPECT_EQ(noise.draws, 4);

  EXPECT_TRUE(torch::equal(trace.at("grid"), ref.at("grid")));
  // The resized images: equal up to float rounding (both are 8-bit PIL resizes scaled to floats).
  EXPECT_CLOSE_TO_GOLDEN(trace.at("control_image"), ref.at("control_image"), 1e-6);
  EXPECT_CLOSE_TO_GOLDEN(trace.at("init_image"), ref.at("init_image"), 1e-6);
  EXPECT_CLOSE_TO_GOLDEN(trace.at("timesteps"), ref.at("timesteps"), 0.0);
  EXPECT_CLOSE_TO_GOLDEN(trace.at("prompt_embeds"), ref.at("prompt_embeds"), kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(trace.at("image_embeds"), ref.at("image_embeds"), kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(trace.at("init_latents"), ref.at("init_latents"), kForwardTolerance);
  for (int i = 0; i <= 2; ++i) {
    SCOPED_TRACE("step " + std::to_string(i));
    const std::string latents = "latents." + std::to_string(i);
    EXPECT_CLOSE_TO_GOLDEN(trace.at(latents), ref.at(latents), kForwardTolerance);
    if (i < 2) {
      const std::string prediction = "noise_pred." + std::to_string(i);
      EXPECT_CLOSE_TO_GOLDEN(trace.at(prediction), ref.at(prediction), kForwardTolerance);
    }
  }
  EXPECT_CLOSE_TO_GOLDEN(trace.at("images"), ref.at("images"), kForwardTolerance);
  // The four views are the reference image's quarters in grid order.
  const torch::Tensor& image = ref.at("images");
  for (int64_t q = 0; q < 4; ++q)
    EXPECT_CLOSE_TO_GOLDEN(out[q], image.narrow(0, (q / 2) * 32, 32).narrow(1, (q % 2) * 32, 32), kForwardTolerance);
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
