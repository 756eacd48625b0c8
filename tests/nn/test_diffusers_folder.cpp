#include "nn/checkpoint/diffusers_folder.h"

#include <gtest/gtest.h>

#include <fstream>
#include <unistd.h>

#include "core/error.h"

namespace fs = std::filesystem;
using namespace u3d::nn;

namespace {

class DiffusersFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("u3d_folder_" + std::to_string(::getpid()));
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  void touch(const fs::path& relative) {
    fs::create_directories((root_ / relative).parent_path());
    std::ofstream(root_ / relative) << "{}";
  }
  std::string error_of(const std::function<void()>& f) {
    try {
      f();
    } catch (const u3d::Error& e) {
      return e.what();
    }
    return "";
  }
  fs::path root_;
};

}  // namespace

TEST_F(DiffusersFolderTest, FindsTheStandardFiles) {
  for (const char* f : {"unet/config.json", "unet/diffusion_pytorch_model.bin", "unet/diffusion_pytorch_model.safetensors",
                        "vae/config.json", "vae/diffusion_pytorch_model.bin", "image_encoder/config.json",
                        "image_encoder/pytorch_model.bin", "feature_extractor/preprocessor_config.json",
                        "scheduler/scheduler_config.json", "unet_state_dict.pth"})
    touch(f);
  DiffusersFolder folder(root_);
  EXPECT_EQ(folder.component_config("unet"), root_ / "unet/config.json");
  EXPECT_EQ(folder.component_weights("unet"), root_ / "unet/diffusion_pytorch_model.safetensors");
  EXPECT_EQ(folder.component_weights("vae"), root_ / "vae/diffusion_pytorch_model.bin");
  EXPECT_EQ(folder.component_weights("image_encoder"), root_ / "image_encoder/pytorch_model.bin");
  EXPECT_EQ(folder.preprocessor_config(), root_ / "feature_extractor/preprocessor_config.json");
  EXPECT_EQ(folder.scheduler_config(), root_ / "scheduler/scheduler_config.json");
  EXPECT_EQ(folder.file("unet_state_dict.pth"), root_ / "unet_state_dict.pth");
}

TEST_F(DiffusersFolderTest, MissingFilesNameTheFileAndTheDownload) {
  touch("unet/config.json");
  DiffusersFolder folder(root_);
  std::string msg = error_of([&] { folder.component_weights("unet"); });
  EXPECT_NE(msg.find((root_ / "unet").string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("diffusion_pytorch_model"), std::string::npos) << msg;
  EXPECT_NE(msg.find("space Wuvin/Unique3D"), std::string::npos) << msg;
  EXPECT_NE(msg.find("lambdalabs/sd-image-variations-diffusers"), std::string::npos) << msg;
  msg = error_of([&] { folder.scheduler_config(); });
  EXPECT_NE(msg.find("scheduler/scheduler_config.json"), std::string::npos) << msg;
  msg = error_of([&] { DiffusersFolder(root_ / "nowhere", "get it from example/repo"); });
  EXPECT_NE(msg.find("nowhere"), std::string::npos) << msg;
  EXPECT_NE(msg.find("example/repo"), std::string::npos) << msg;
}
