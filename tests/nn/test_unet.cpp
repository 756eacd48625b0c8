#include "nn/models/unet.h"

#include <gtest/gtest.h>

#include "golden.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

class UNetBase : public ::testing::Test {
 protected:
  void SetUp() override {
    auto config = UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json");
    unet = UNet2DConditionModel(config, torch::TensorOptions());
    load_golden_weights(*unet, "unet_base");
    in = golden_tensors("unet_base", "inputs");
    ref = golden_tensors("unet_base", "outputs");
  }
  UNet2DConditionModel unet{nullptr};
  TensorMap in, ref;
};

TEST_F(UNetBase, SquareForwardWithIntermediates) {
  torch::NoGradGuard no_grad;
  TensorMap trace;
  UNetExtras extras;
  extras.trace = &trace;
  torch::Tensor out = unet->forward(in["a.sample"], in["a.timestep"], in["a.encoder_hidden_states"], extras);
  EXPECT_CLOSE_TO_GOLDEN(out, ref["a.sample_out"], kForwardTolerance);
  for (const char* name : {"time_proj", "time_embedding", "conv_in", "down_blocks.0", "down_blocks.1", "mid_block",
                           "up_blocks.0", "up_blocks.1"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(trace.count(name));
    EXPECT_CLOSE_TO_GOLDEN(trace[name], ref[std::string("a.internal.") + name], kForwardTolerance);
  }
}

TEST_F(UNetBase, NonSquareForwardWithIntegerTimestep) {
  torch::NoGradGuard no_grad;
  ASSERT_EQ(in["b.timestep"].scalar_type(), torch::kInt64);
  torch::Tensor out = unet->forward(in["b.sample"], in["b.timestep"], in["b.encoder_hidden_states"]);
  EXPECT_CLOSE_TO_GOLDEN(out, ref["b.sample_out"], kForwardTolerance);
}

TEST_F(UNetBase, RejectsBadInputs) {
  torch::NoGradGuard no_grad;
  EXPECT_THROW(unet->forward(torch::zeros({1, 4, 15, 16}), torch::tensor(1.0), torch::zeros({1, 1, 16})), u3d::Error);
  EXPECT_THROW(unet->forward(torch::zeros({2, 4, 16, 16}), torch::tensor({1.0, 2.0, 3.0}), torch::zeros({2, 1, 16})),
               u3d::Error);
  EXPECT_THROW(unet->forward(torch::zeros({2, 4, 16, 16}), torch::tensor(1.0), torch::zeros({1, 1, 16})), u3d::Error);
}

TEST(UNetConfig, RejectsUnsupportedSettings) {
  auto json = golden_config("unet_base");
  json["use_linear_projection"] = true;
  EXPECT_THROW(UNetConfig::from_json(json, "cfg"), u3d::Error);
  json = golden_config("unet_base");
  json["down_block_types"] = {"CrossAttnDownBlock2D", "SimpleDownBlock2D"};
  EXPECT_THROW(UNetConfig::from_json(json, "cfg"), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

// Nothing in the network is tied to fp32: built in float64 it reproduces the reference too.
TEST(UNetDtype, Float64Forward) {
  torch::NoGradGuard no_grad;
  auto config = UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json");
  UNet2DConditionModel unet(config, torch::TensorOptions().dtype(torch::kDouble));
  load_golden_weights(*unet, "unet_base");
  EXPECT_EQ(unet->conv_in->weight.scalar_type(), torch::kDouble);
  auto in = golden_tensors("unet_base", "inputs");
  auto ref = golden_tensors("unet_base", "outputs");
  torch::Tensor out = unet->forward(in["a.sample"].to(torch::kDouble), in["a.timestep"],
                                    in["a.encoder_hidden_states"].to(torch::kDouble));
  EXPECT_EQ(out.scalar_type(), torch::kDouble);
  EXPECT_CLOSE_TO_GOLDEN(out, ref["a.sample_out"], kForwardTolerance);
}

}  // namespace
}  // namespace u3d::nn
