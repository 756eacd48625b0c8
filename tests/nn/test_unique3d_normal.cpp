// The normal-map stage loaded as the official app loads it (an sd-image-variations folder plus
// ckpt/image2normal/unet_state_dict.pth), made of the tiny golden models, reproduces the official
// pipeline's images, with the reference UNet taken from the folder or from the .pth's "ref_unet." keys.
#include "nn/pipelines/unique3d_normal.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "golden.h"
#include "nn/precision.h"
#include "required_skip.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;
namespace fs = std::filesystem;

class NormalFolders : public ::testing::Test {
 protected:
  void SetUp() override {
    root = fs::temp_directory_path() / ("u3d_test_image2normal_" + std::to_string(::getpid()));
    base = root / "sd-image-variations-diffusers";
    unique3d = root / "image2normal";
    fs::remove_all(root);
    write_image_variations_folder(base, /*unet_weights=*/true);
    fs::create_directories(unique3d);
  }
  void TearDown() override { fs::remove_all(root); }

  // The golden case's two views (the test image and its mirror) and settings.
  static std::vector<torch::Tensor> golden_views() {
    const torch::Tensor image = golden_tensors("unet_mv", "inputs")["pipe.test_image_uint8"];
    return {image, image.flip(1).contiguous()};
  }
  static NormalSettings golden_settings(bool free_networks_as_done) {
    NormalSettings settings;
    settings.size = 32;
    settings.steps = 2;
    settings.free_networks_as_done = free_networks_as_done;
    return settings;
  }

  // Returns the model after its run.
  std::unique_ptr<NormalModel> expect_official_images(Precision precision, double tolerance,
                                                      bool free_networks_as_done = false) {
    auto model = NormalModel::load(base, unique3d, precision);
    auto ref = golden_tensors("unet_ref", "outputs");
    GoldenPipelineNoise noise(golden_tensors("unet_ref", "inputs"), /*draws_initial_latents=*/true);
    torch::Tensor images = model->run(golden_views(), golden_settings(free_networks_as_done), noise);
    EXPECT_EQ(noise.draws, 3);
    if (precision == Precision::kFp32)
      EXPECT_CLOSE_TO_GOLDEN(images, ref["pipe.images"], tolerance);
    else
      EXPECT_RELATIVE_TO_GOLDEN(images, ref["pipe.images"], tolerance);
    return model;
  }

  fs::path root, base, unique3d;
};

TEST_F(NormalFolders, ReferenceUNetFromTheFolder) {
  fs::copy_file(golden_dir("unet_ref") / "weights.pth", unique3d / "unet_state_dict.pth");
  expect_official_images(Precision::kFp32, 1e-4);
}

TEST_F(NormalFolders, ReferenceUNetFromTheFolderInBf16) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  fs::copy_file(golden_dir("unet_ref") / "weights.pth", unique3d / "unet_state_dict.pth");
  expect_official_images(Precision::kBf16, 2e-2);
}

TEST_F(NormalFolders, ReferenceUNetFromTheCheckpoint) {
  // The main UNet and the reference (unet_base) under "ref_unet." (tests/data/nn/unet_ref/make_pth.py).
  fs::copy_file(golden_dir("unet_ref") / "weights_ref_unet.pth", unique3d / "unet_state_dict.pth");
  // The folder's own UNet weights are then not what the reference uses: spoil them.
  fs::remove(base / "unet" / "diffusion_pytorch_model.safetensors");
  TensorMap spoiled = golden_tensors("unet_base", "weights");
  for (auto& [key, value] : spoiled) value = torch::zeros_like(value);
  save_safetensors(spoiled, base / "unet" / "diffusion_pytorch_model.safetensors");
  expect_official_images(Precision::kFp32, 1e-4);
}

// The pipeline stages free each network once the run is past it (the CLIP encoder after the
// embeddings, both UNets before decoding): the images are the same, and the spent model says so when
// asked to run again instead of crashing.
TEST_F(NormalFolders, FreeingTheNetworksAsDoneKeepsTheImages) {
  fs::copy_file(golden_dir("unet_ref") / "weights.pth", unique3d / "unet_state_dict.pth");
  auto model = expect_official_images(Precision::kFp32, 1e-4, /*free_networks_as_done=*/true);
  EXPECT_EQ(model->unet, nullptr);
  EXPECT_TRUE(model->parts.image_encoder.is_empty());
  EXPECT_FALSE(model->parts.vae.is_empty());
  const torch::Tensor image = golden_tensors("unet_mv", "inputs")["pipe.test_image_uint8"];
  SeededNoise noise(1);
  NormalSettings settings;
  settings.size = 32;
  settings.steps = 1;
  try {
    model->run({image}, settings, noise);
    FAIL() << "no error";
  } catch (const u3d::Error& e) {
    EXPECT_NE(std::string(e.what()).find("freed"), std::string::npos) << e.what();
  }
}

// The pipeline stage loads the UNets only once the views are encoded and the CLIP encoder is freed:
// the same images, and sampling without the UNets says what is missing.
TEST_F(NormalFolders, UNetsLoadedAfterTheEncodingKeepTheImages) {
  fs::copy_file(golden_dir("unet_ref") / "weights.pth", unique3d / "unet_state_dict.pth");
  auto model = NormalModel::load_conditioning(base, unique3d, Precision::kFp32);
  EXPECT_EQ(model->unet, nullptr);
  const NormalSettings settings = golden_settings(/*free_networks_as_done=*/true);
  const ImageConditions conditions = model->encode(golden_views(), settings);
  EXPECT_TRUE(model->parts.image_encoder.is_empty());
  GoldenPipelineNoise noise(golden_tensors("unet_ref", "inputs"), /*draws_initial_latents=*/true);
  try {
    model->sample(conditions, settings, noise);
    FAIL() << "no error";
  } catch (const u3d::Error& e) {
    EXPECT_NE(std::string(e.what()).find("load_unet"), std::string::npos) << e.what();
  }
  EXPECT_EQ(noise.draws, 0);
  model->load_unet();
  const torch::Tensor images = model->sample(conditions, settings, noise);
  EXPECT_EQ(noise.draws, 3);
  EXPECT_CLOSE_TO_GOLDEN(images, golden_tensors("unet_ref", "outputs")["pipe.images"], 1e-4);
  EXPECT_EQ(model->unet, nullptr);  // freed again before the decoding
}

TEST_F(NormalFolders, MissingFilesAreNamedBeforeLoading) {
  for (bool conditioning_only : {false, true}) {
    try {
      if (conditioning_only)
        NormalModel::load_conditioning(base, unique3d, Precision::kFp32);
      else
        NormalModel::load(base, unique3d, Precision::kFp32);
      FAIL() << "no error";
    } catch (const u3d::Error& e) {
      EXPECT_NE(std::string(e.what()).find("unet_state_dict.pth"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace u3d::nn
