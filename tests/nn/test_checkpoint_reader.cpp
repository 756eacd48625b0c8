// Checking checkpoints without loading them (nn/checkpoint/checkpoint_reader.h): the header-only readers
// (inspect_safetensors, inspect_pth) give the shapes and dtypes loading gives and fail on truncated
// files; the loaders in check mode accept the folders they load and name the file that does not match;
// save_pth writes what load_pth reads.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "golden.h"
#include "nn/checkpoint/checkpoint_reader.h"
#include "nn/checkpoint/pth_reader.h"
#include "nn/checkpoint/pth_writer.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/pipelines/unique3d_multiview.h"
#include "nn/pipelines/unique3d_normal.h"

namespace u3d::nn {
namespace {

namespace fs = std::filesystem;
using test::golden_dir;

class CheckpointReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("u3d_ckpt_check_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A copy of `file` without its last `bytes` bytes.
  fs::path truncated_copy(const fs::path& file, uintmax_t bytes) {
    const fs::path out = dir_ / ("truncated" + file.extension().string());
    fs::copy_file(file, out, fs::copy_options::overwrite_existing);
    fs::resize_file(out, fs::file_size(file) - bytes);
    return out;
  }

  static TensorMap mixed_tensors() {
    TensorMap t;
    t["a.weight"] = torch::randn({3, 4});
    t["a.bias"] = torch::randn({4}).to(torch::kHalf);
    t["b.transposed"] = torch::randn({5, 2}).t();  // non-contiguous: saved contiguous
    t["c.bf16"] = torch::randn({2, 2, 2}).to(torch::kBFloat16);
    t["d.long"] = torch::tensor({int64_t(1) << 40, int64_t(-3)});
    t["e.scalar"] = torch::tensor(2.5f);
    return t;
  }

  static void expect_same_shapes(const TensorMap& actual, const TensorMap& expected) {
    ASSERT_EQ(actual.size(), expected.size());
    for (const auto& [name, tensor] : expected) {
      ASSERT_TRUE(actual.count(name)) << name;
      EXPECT_EQ(actual.at(name).sizes(), tensor.sizes()) << name;
      EXPECT_EQ(actual.at(name).scalar_type(), tensor.scalar_type()) << name;
      EXPECT_TRUE(actual.at(name).is_meta()) << name;
    }
  }

  fs::path dir_;
};

TEST_F(CheckpointReaderTest, SavePthWritesWhatLoadPthReads) {
  const TensorMap tensors = mixed_tensors();
  save_pth(tensors, dir_ / "weights.pth");
  const TensorMap loaded = load_pth(dir_ / "weights.pth");
  ASSERT_EQ(loaded.size(), tensors.size());
  for (const auto& [name, tensor] : tensors) {
    ASSERT_TRUE(loaded.count(name)) << name;
    EXPECT_EQ(loaded.at(name).scalar_type(), tensor.scalar_type()) << name;
    EXPECT_TRUE(torch::equal(loaded.at(name), tensor)) << name;
  }
  // A real torch.save file survives a round trip through the writer.
  const TensorMap golden = load_pth(golden_dir("unet_mv") / "weights.pth");
  save_pth(golden, dir_ / "resaved.pth");
  const TensorMap resaved = load_pth(dir_ / "resaved.pth");
  ASSERT_EQ(resaved.size(), golden.size());
  for (const auto& [name, tensor] : golden) EXPECT_TRUE(torch::equal(resaved.at(name), tensor)) << name;
}

TEST_F(CheckpointReaderTest, InspectGivesShapesAndDtypesWithoutData) {
  const TensorMap tensors = mixed_tensors();
  save_pth(tensors, dir_ / "weights.pth");
  save_safetensors(tensors, dir_ / "weights.safetensors");
  expect_same_shapes(inspect_pth(dir_ / "weights.pth"), tensors);
  expect_same_shapes(inspect_safetensors(dir_ / "weights.safetensors"), tensors);
  expect_same_shapes(inspect_pth(golden_dir("unet_mv") / "weights.pth"), load_pth(golden_dir("unet_mv") / "weights.pth"));
}

TEST_F(CheckpointReaderTest, TruncatedFilesFailInspection) {
  const fs::path pth = golden_dir("unet_mv") / "weights.pth";
  const fs::path st = golden_dir("unet_mv") / "weights.safetensors";
  for (uintmax_t cut : {uintmax_t(1), uintmax_t(4096), fs::file_size(pth) / 2}) {
    const fs::path bad = truncated_copy(pth, cut);
    EXPECT_THROW(inspect_pth(bad), Error) << "cut " << cut;
  }
  for (uintmax_t cut : {uintmax_t(1), fs::file_size(st) / 2}) {
    const fs::path bad = truncated_copy(st, cut);
    try {
      inspect_safetensors(bad);
      ADD_FAILURE() << "no error for a safetensors file cut by " << cut;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
    }
  }
}

// A multi-view folder of the tiny golden models, as the loaders read it.
class CheckModeTest : public CheckpointReaderTest {
 protected:
  void SetUp() override {
    CheckpointReaderTest::SetUp();
    test::write_image_variations_folder(dir_ / "img2mvimg", /*unet_weights=*/false);
    test::copy_into_folder(dir_, {{golden_dir("unet_mv") / "weights.pth", "img2mvimg/unet_state_dict.pth"}});
  }
  const CheckpointReader check_{CheckpointReader::Mode::kCheck};
};

TEST_F(CheckModeTest, AcceptsWhatLoads) {
  const auto checked = MultiViewModel::load(dir_ / "img2mvimg", Precision::kFp32, check_);
  EXPECT_TRUE(checked->unet->conv_in->weight.is_meta());
  const auto loaded = MultiViewModel::load(dir_ / "img2mvimg", Precision::kFp32);
  EXPECT_FALSE(loaded->unet->conv_in->weight.is_meta());
}

TEST_F(CheckModeTest, NamesTheFileThatDoesNotMatch) {
  // The normal model's UNet where the multi-view one belongs: 4-channel conv_in, extra tensors.
  const fs::path unet = dir_ / "img2mvimg" / "unet_state_dict.pth";
  fs::copy_file(golden_dir("unet_ref") / "weights.pth", unet, fs::copy_options::overwrite_existing);
  try {
    MultiViewModel::load(dir_ / "img2mvimg", Precision::kFp32, check_);
    ADD_FAILURE() << "no error for a mismatched checkpoint";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(unet.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("does not match"), std::string::npos) << msg;
  }
  // And a truncated VAE.
  const fs::path vae = dir_ / "img2mvimg" / "vae" / "diffusion_pytorch_model.safetensors";
  fs::copy_file(golden_dir("unet_mv") / "weights.pth", unet, fs::copy_options::overwrite_existing);
  fs::resize_file(vae, fs::file_size(vae) - 100);
  EXPECT_THROW(MultiViewModel::load(dir_ / "img2mvimg", Precision::kFp32, check_), Error);
}

}  // namespace
}  // namespace u3d::nn
