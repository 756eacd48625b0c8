// The image-to-four-views stage loaded from a folder in the official ckpt/img2mvimg layout, made of the
// tiny golden models, reproduces the official pipeline's images; a missing file is reported first.
#include "nn/pipelines/unique3d_multiview.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "golden.h"
#include "nn/precision.h"
#include "nn/schedulers/noise_source.h"
#include "required_skip.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;
namespace fs = std::filesystem;

class MultiViewFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    root = fs::temp_directory_path() / ("u3d_test_img2mvimg_" + std::to_string(::getpid()));
    fs::remove_all(root);
    // The sd-image-variations stand-in plus Unique3D's unet_state_dict.pth (ckpt/img2mvimg holds both).
    write_image_variations_folder(root, /*unet_weights=*/false);
    copy_into_folder(root, {{golden_dir("unet_mv") / "weights.pth", "unet_state_dict.pth"}});
  }
  void TearDown() override { fs::remove_all(root); }

  // The golden case's 2-step run through the stage loaded from the folder.
  torch::Tensor run_golden(MultiViewModel& model) {
    auto in = golden_tensors("unet_mv", "inputs");
    MultiViewSettings settings;
    settings.size = 32;
    settings.steps = 2;
    GoldenPipelineNoise noise(in, /*draws_initial_latents=*/true);
    torch::Tensor images = model.run(in["pipe.test_image_uint8"], settings, noise);
    EXPECT_EQ(noise.draws, 3);
    return images;
  }

  fs::path root;
};

TEST_F(MultiViewFolder, ReproducesTheOfficialPipeline) {
  auto model = MultiViewModel::load(root, Precision::kFp32);
  EXPECT_EQ(model->unet->config.in_channels, 8);
  EXPECT_CLOSE_TO_GOLDEN(run_golden(*model), golden_tensors("unet_mv", "outputs")["pipe.images"], 1e-4);
}

// As a user runs it: seeded, nothing injected. make_seeded.py (in the case folder) ran the official
// pipeline with torch.Generator().manual_seed(seed) for two seeds.
TEST_F(MultiViewFolder, ReproducesTheOfficialSeededRuns) {
  auto model = MultiViewModel::load(root, Precision::kFp32);
  const TensorMap seeded = golden_tensors("unet_mv", "seeded");
  const torch::Tensor photo = golden_tensors("unet_mv", "inputs")["pipe.test_image_uint8"];
  MultiViewSettings settings;
  settings.size = 32;
  settings.steps = 2;
  for (uint64_t seed : {7, 2024}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    SeededNoise noise(seed);
    EXPECT_CLOSE_TO_GOLDEN(model->run(photo, settings, noise), seeded.at("seed" + std::to_string(seed) + ".images"), 1e-4);
  }
}

TEST_F(MultiViewFolder, Bf16StaysClose) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  auto model = MultiViewModel::load(root, Precision::kBf16);
  EXPECT_RELATIVE_TO_GOLDEN(run_golden(*model), golden_tensors("unet_mv", "outputs")["pipe.images"], 2e-2);
}

TEST_F(MultiViewFolder, MissingOrMismatchedFilesAreNamed) {
  fs::remove(root / "vae" / "diffusion_pytorch_model.safetensors");
  try {
    MultiViewModel::load(root, Precision::kFp32);
    FAIL() << "no error";
  } catch (const u3d::Error& e) {
    EXPECT_NE(std::string(e.what()).find("vae"), std::string::npos) << e.what();
  }
  fs::copy_file(golden_dir("vae") / "weights.safetensors", root / "vae" / "diffusion_pytorch_model.safetensors");

  // unet_state_dict.pth that is not a torch checkpoint.
  fs::rename(root / "unet_state_dict.pth", root / "real.pth");
  fs::copy_file(golden_dir("unet_base") / "weights.safetensors", root / "unet_state_dict.pth");
  try {
    MultiViewModel::load(root, Precision::kFp32);
    FAIL() << "no error";
  } catch (const u3d::Error& e) {
    EXPECT_NE(std::string(e.what()).find("unet_state_dict.pth"), std::string::npos) << e.what();
  }
  fs::remove(root / "unet_state_dict.pth");
  fs::rename(root / "real.pth", root / "unet_state_dict.pth");

  // A UNet config that does not fit the weights: every mismatch is named.
  nlohmann::json config = golden_config("unet_base");
  config["block_out_channels"] = {16, 32};
  std::ofstream(root / "unet" / "config.json") << config.dump();
  try {
    MultiViewModel::load(root, Precision::kFp32);
    FAIL() << "no error";
  } catch (const u3d::Error& e) {
    EXPECT_NE(std::string(e.what()).find("conv_in.weight"), std::string::npos) << e.what();
  }
  EXPECT_THROW(MultiViewModel::load(root, Precision::kFp16), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
