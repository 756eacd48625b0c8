// U^2-Net (the rembg u2net.onnx architecture, all widths / 8) and ISNet (/ 8) against their golden cases,
// loaded from the state dict with BatchNorm (folded on loading), from the ONNX exports (BatchNorm folded
// by the exporter, anonymous initializer names) and from the fp16 file in the layout of imgly's model.
#include <gtest/gtest.h>

#include <functional>

#include "golden.h"
#include "nn/checkpoint/onnx_weights.h"
#include "nn/models/u2net.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;
namespace fs = std::filesystem;

// The cases' suggestion for fp32 (their references differ from fp64 by 2e-6 on the masks and 2e-5 on the
// ISNet features, which reach 30).
constexpr double kMaskTolerance = 1e-4;
constexpr double kFeatureTolerance = 2e-4;

const fs::path kU2NetDiv8 = golden_dir("u2net_tiny") / "u2net_div8";

TEST(U2Net, Div8MatchesTheReferenceFromEveryFormat) {
  torch::NoGradGuard no_grad;
  const torch::Tensor input = golden_tensors("u2net_tiny", "inputs").at("input");
  const TensorMap expected = load_safetensors(kU2NetDiv8 / "outputs.safetensors");
  for (const char* file : {"weights.safetensors", "u2net_div8_op11.onnx", "u2net_div8_op17.onnx"}) {
    SCOPED_TRACE(file);
    U2Net net = load_u2net(kU2NetDiv8 / file);
    EXPECT_FALSE(net->config.isnet);
    // U2NET's stage1 is RSU7(3, 32, 64) and stage5d RSU4F(1024, 256, 512), here divided by 8.
    EXPECT_EQ(net->config.stages[0].in, 3);
    EXPECT_EQ(net->config.stages[0].mid, 4);
    EXPECT_EQ(net->config.stages[0].out, 8);
    EXPECT_EQ(net->config.stages[6].in, 128);
    const std::vector<torch::Tensor> out = net->forward(input);
    ASSERT_EQ(out.size(), 7u);
    const char* names[] = {"d0", "d1", "d2", "d3", "d4", "d5", "d6"};
    for (int i = 0; i < 7; ++i) {
      SCOPED_TRACE(names[i]);
      EXPECT_CLOSE_TO_GOLDEN(out[i], expected.at(names[i]), kMaskTolerance);
    }
  }
}

TEST(U2Net, OnnxFoldedConvsEqualTheFoldedStateDict) {
  TensorMap folded = load_safetensors(kU2NetDiv8 / "weights.safetensors");
  fold_rebnconv_batchnorm(folded, "weights");
  const TensorMap from_onnx = read_u2net_weights(kU2NetDiv8 / "u2net_div8_op17.onnx");
  ASSERT_EQ(from_onnx.size(), folded.size());
  double worst = 0;
  for (const auto& [name, tensor] : folded) worst = std::max(worst, max_abs_diff(from_onnx.at(name), tensor));
  std::printf("  ONNX-folded vs our fold: max abs %.3g\n", worst);
  EXPECT_LE(worst, 1e-6);  // the case measured 8.1e-8 against a float64 fold
}

TEST(U2Net, IsNetMatchesTheReference) {
  torch::NoGradGuard no_grad;
  const torch::Tensor input = golden_tensors("isnet_tiny", "inputs").at("input");
  const TensorMap expected = golden_tensors("isnet_tiny", "outputs");
  const char* names[] = {"d1", "d2", "d3", "d4", "d5", "d6", "hx1d", "hx2d", "hx3d", "hx4d", "hx5d", "hx6"};
  // The fp16 file's weights are the fp32 ones rounded; its reference (fp16w.*) is fp32 math on them.
  for (const auto& [file, prefix] : std::vector<std::pair<std::string, std::string>>{
           {"weights.safetensors", ""}, {"isnet_div8_op17.onnx", ""}, {"isnet_div8_op17_fp16.onnx", "fp16w."}}) {
    SCOPED_TRACE(file);
    U2Net net = load_u2net(golden_dir("isnet_tiny") / file);
    EXPECT_TRUE(net->config.isnet);
    EXPECT_EQ(net->config.stages[0].in, 8);  // conv_in 3 -> 64 / 8
    const std::vector<torch::Tensor> out = net->forward(input);
    ASSERT_EQ(out.size(), 12u);
    for (int i = 0; i < 12; ++i) {
      SCOPED_TRACE(names[i]);
      EXPECT_CLOSE_TO_GOLDEN(out[i], expected.at(prefix + names[i]), i < 6 ? kMaskTolerance : kFeatureTolerance);
    }
  }
}

TEST(U2Net, Fp16InitializersAreReadAsStored) {
  const OnnxGraph graph = load_onnx(golden_dir("isnet_tiny") / "isnet_div8_op17_fp16.onnx");
  const TensorMap fp32 = read_u2net_weights(golden_dir("isnet_tiny") / "isnet_div8_op17.onnx");
  const TensorMap fp16 = read_u2net_weights(golden_dir("isnet_tiny") / "isnet_div8_op17_fp16.onnx");
  EXPECT_EQ(graph.initializers.size(), 238u);
  for (const auto& [name, tensor] : fp16) {
    EXPECT_EQ(tensor.scalar_type(), torch::kHalf) << name;
    EXPECT_TRUE(torch::equal(tensor, fp32.at(name).to(torch::kHalf))) << name;  // the file is the fp32 one rounded
  }
}

void expect_error(const std::function<void()>& load, std::initializer_list<std::string> fragments) {
  try {
    load();
    ADD_FAILURE() << "no error";
  } catch (const u3d::Error& e) {
    const std::string msg = e.what();
    for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
  }
}

TEST(U2Net, WrongOrIncompleteFilesNameTheTensor) {
  // An RRDBNet export is not a U^2-Net: 21 Conv nodes against 119.
  expect_error([] { load_u2net(golden_dir("realesrgan_tiny") / "rrdbnet_tiny_op17.onnx"); },
               {"rrdbnet_tiny_op17.onnx", "21 Conv nodes", "119"});
  // A state dict whose BatchNorm lost a tensor.
  TensorMap weights = load_safetensors(kU2NetDiv8 / "weights.safetensors");
  weights.erase("stage3.rebnconv2.bn_s1.running_var");
  expect_error([&] { fold_rebnconv_batchnorm(weights, "cut.safetensors"); },
               {"cut.safetensors", "stage3.rebnconv2.bn_s1.running_var"});
  // A conv of the wrong width: the strict loader names it.
  TensorMap folded = load_safetensors(kU2NetDiv8 / "weights.safetensors");
  fold_rebnconv_batchnorm(folded, "w");
  folded["stage2.rebnconv3.conv_s1.weight"] = torch::zeros({4, 5, 3, 3});
  expect_error([&] { build_u2net(folded, "wide.safetensors"); },
               {"wide.safetensors", "stage2.rebnconv3.conv_s1.weight"});
}

}  // namespace
}  // namespace u3d::nn
