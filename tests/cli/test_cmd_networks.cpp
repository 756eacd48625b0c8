// The network subcommands on the tiny models: `upscale` and `matte` write the networks' outputs; bad
// inputs give a clear message, a non-zero exit and no output. (The diffusion stages run in
// tests/pipeline/test_network_stages.cpp and test_generate.cpp, on the tiny models at a small size.)
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/image.h"
#include "core/synthetic_views.h"
#include "nn/pipelines/input_photo.h"
#include "nn/pipelines/matting.h"
#include "nn/pipelines/upscale.h"
#include "pipeline/tensor_image.h"
#include "pipeline/tiny_model_folder.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

struct CliResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

CliResult run_cli(const std::string& args, const fs::path& log) {
  const std::string cmd = std::string(UNIQUE3D_CLI) + " " + args + " > " + log.string() + " 2>&1";
  CliResult r;
  r.status = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.output = ss.str();
  return r;
}

class NetworkCommands : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir = new fs::path(testing::fresh_temp_dir("cli_networks"));
    testing::write_tiny_model_folder(*dir / "models");
    testing::write_disk_photo(*dir / "photo.png");
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir);
    delete dir;
  }
  static std::string models() { return " --models " + (*dir / "models").string(); }
  static fs::path* dir;
};
fs::path* NetworkCommands::dir = nullptr;

// The commands write what the networks give on the same pixels: `upscale` the upscaler's output,
// `matte` the photo with the matting model's mask as its alpha.
TEST_F(NetworkCommands, UpscaleAndMatteWriteTheNetworksOutputs) {
  Image photo(24, 20, 3, 0.3f);
  for (int y = 4; y < 16; ++y)
    for (int x = 6; x < 18; ++x) photo.pixel(x, y)[0] = 0.9f, photo.pixel(x, y)[1] = 0.1f + 0.05f * (y - 4);
  save_image(photo, *dir / "small.png");
  const torch::Tensor pixels = image_to_uint8(load_image(*dir / "small.png"));
  CliResult r = run_cli(
      "upscale " + (*dir / "small.png").string() + " -o " + (*dir / "x4.png").string() + models() + " --dtype fp32",
      *dir / "u.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const torch::Tensor x4 = image_to_uint8(load_image(*dir / "x4.png"));
  const torch::Tensor upscaled =
      nn::UpscaleModel::load(*dir / "models" / "realesrgan-x4.onnx", nn::Precision::kFp32)->upscale(pixels);
  ASSERT_EQ(x4.sizes(), torch::IntArrayRef({80, 96, 3}));
  EXPECT_TRUE(torch::equal(x4, upscaled));

  r = run_cli(
      "matte " + (*dir / "small.png").string() + " -o " + (*dir / "cut.png").string() + models() + " --dtype fp32",
      *dir / "m.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const torch::Tensor cut = image_to_uint8(load_image(*dir / "cut.png"));
  const auto matting = nn::MattingModel::load(*dir / "models" / "u2net.onnx", nn::Precision::kFp32);
  ASSERT_EQ(cut.sizes(), torch::IntArrayRef({20, 24, 4}));
  EXPECT_TRUE(torch::equal(cut, nn::matte_photo(pixels, *matting, /*raw_matte=*/false)));
  // --raw-matte: the network's mask as it is, rembg's cut-out (colours times the mask).
  r = run_cli("matte " + (*dir / "small.png").string() + " -o " + (*dir / "raw.png").string() + models() +
                  " --dtype fp32 --raw-matte",
              *dir / "m2.log");
  ASSERT_EQ(r.status, 0) << r.output;
  const torch::Tensor raw = image_to_uint8(load_image(*dir / "raw.png"));
  const torch::Tensor mask = matting->matte(pixels);
  EXPECT_GT(mask.max().item<int>() - mask.min().item<int>(), 10);  // the comparison below can tell masks apart
  EXPECT_TRUE(torch::equal(raw.select(2, 3), mask));
  EXPECT_TRUE(torch::equal(raw, nn::cutout(pixels, mask, nn::MattingStyle::kRembg)));
}

TEST_F(NetworkCommands, BadInputsAreNamedAndWriteNothing) {
  const fs::path out = *dir / "never";
  // A "prepared" image without transparency, and a photo too small to prepare.
  Image opaque(64, 64, 3, 0.5f);
  save_image(opaque, *dir / "opaque.png");
  CliResult r = run_cli("multiview " + (*dir / "opaque.png").string() + " --prepared -o " + out.string() + models(),
                        *dir / "b1.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("opaque.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("alpha"), std::string::npos) << r.output;
  save_image(Image(40, 64, 3, 0.5f), *dir / "narrow.png");
  r = run_cli("multiview " + (*dir / "narrow.png").string() + " -o " + out.string() + models(), *dir / "b1b.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("narrow.png is 40x64: too small"), std::string::npos) << r.output;
  // A model folder without the multi-view checkpoint.
  fs::create_directories(*dir / "empty_models");
  r = run_cli("multiview " + (*dir / "photo.png").string() + " -o " + out.string() + " --models " +
                  (*dir / "empty_models").string(),
              *dir / "b2.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("img2mvimg"), std::string::npos) << r.output;
  // fp16 needs CUDA.
  r = run_cli("multiview " + (*dir / "photo.png").string() + " -o " + out.string() + models() + " --dtype fp16",
              *dir / "b3.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("fp16"), std::string::npos) << r.output;
  // normals: a folder without views.
  r = run_cli("normals " + (*dir / "empty_models").string() + " -o " + out.string() + models(), *dir / "b4.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("front_rgb.png"), std::string::npos) << r.output;
  // An output the image writer cannot write is refused before the network runs.
  r = run_cli("upscale " + (*dir / "photo.png").string() + " -o " + (*dir / "x4.txt").string() + models(),
              *dir / "b5.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("x4.txt"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("upscaling"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(NetworkCommands, DoctorChecksEveryNetworkAndSaysWhatCanRun) {
  CliResult r = run_cli("doctor" + models(), *dir / "d.log");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("cpu "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("generate: ready"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("FAILED"), std::string::npos) << r.output;

  // Without the refinement's ControlNet and with a truncated normal model: named, with the consequence.
  const fs::path broken = *dir / "models_doctor";
  fs::copy(*dir / "models", broken, fs::copy_options::recursive);
  fs::remove_all(broken / "controlnet-tile");
  r = run_cli("doctor --quick --models " + broken.string(), *dir / "d2.log");
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("controlnet-tile"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ready with --no-refine only"), std::string::npos) << r.output;
  const fs::path normal_unet = broken / "image2normal" / "unet_state_dict.pth";
  fs::resize_file(normal_unet, fs::file_size(normal_unet) / 2);
  r = run_cli("doctor --quick --models " + broken.string(), *dir / "d3.log");
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(normal_unet.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("generate: not ready"), std::string::npos) << r.output;
  fs::remove_all(broken);

  r = run_cli("doctor --models " + (*dir / "no_such_folder").string(), *dir / "d4.log");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("no_such_folder"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace u3d
