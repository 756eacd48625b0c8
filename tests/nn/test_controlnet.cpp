#include "nn/models/controlnet.h"

#include <gtest/gtest.h>

#include "golden.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

TEST(ControlNet, ResidualsAndUNetWithResidualsMatchDiffusers) {
  torch::NoGradGuard no_grad;
  ControlNetModel controlnet(ControlNetConfig::from_json(golden_config("controlnet"), "controlnet/config.json"),
                             torch::TensorOptions());
  load_golden_weights(*controlnet, "controlnet");
  UNet2DConditionModel unet(UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json"),
                            torch::TensorOptions());
  load_golden_weights(*unet, "unet_base");
  auto in = golden_tensors("controlnet", "inputs");
  auto ref = golden_tensors("controlnet", "outputs");
  const double scale = in["conditioning_scale"].item<double>();
  EXPECT_FLOAT_EQ(scale, 0.7);

  ControlNetOutput out = controlnet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"],
                                             in["controlnet_cond"], scale);
  ASSERT_EQ(out.down_block_res_samples.size(), 4u);
  for (size_t i = 0; i < out.down_block_res_samples.size(); ++i)
    EXPECT_CLOSE_TO_GOLDEN(out.down_block_res_samples[i], ref["down_block_res_samples." + std::to_string(i)],
                           kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(out.mid_block_res_sample, ref["mid_block_res_sample"], kForwardTolerance);

  UNetExtras extras;
  extras.down_block_additional_residuals = out.down_block_res_samples;
  extras.mid_block_additional_residual = out.mid_block_res_sample;
  EXPECT_CLOSE_TO_GOLDEN(unet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"], extras),
                         ref["unet_sample_out_with_residuals"], kForwardTolerance);
}

// The refinement embeds its control image once a run and gives that embedding to every step: the
// residuals are forward()'s, bit for bit.
TEST(ControlNet, AnEmbeddedControlImageGivesTheSameResiduals) {
  torch::NoGradGuard no_grad;
  ControlNetModel controlnet(ControlNetConfig::from_json(golden_config("controlnet"), "controlnet/config.json"),
                             torch::TensorOptions());
  load_golden_weights(*controlnet, "controlnet");
  auto in = golden_tensors("controlnet", "inputs");
  ControlNetOutput direct = controlnet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"],
                                                in["controlnet_cond"]);
  const torch::Tensor embedded = controlnet->embed_condition(in["controlnet_cond"]);
  ControlNetOutput reused = controlnet->forward_embedded(in["sample"], in["timestep"], in["encoder_hidden_states"],
                                                         embedded);
  ASSERT_EQ(reused.down_block_res_samples.size(), direct.down_block_res_samples.size());
  for (size_t i = 0; i < direct.down_block_res_samples.size(); ++i)
    EXPECT_TRUE(torch::equal(reused.down_block_res_samples[i], direct.down_block_res_samples[i])) << i;
  EXPECT_TRUE(torch::equal(reused.mid_block_res_sample, direct.mid_block_res_sample));
  // An embedding of another batch size or resolution is refused.
  EXPECT_THROW(controlnet->forward_embedded(in["sample"], in["timestep"], in["encoder_hidden_states"],
                                            embedded.narrow(0, 0, 1)),
               u3d::Error);
  EXPECT_THROW(controlnet->forward_embedded(in["sample"], in["timestep"], in["encoder_hidden_states"],
                                            embedded.narrow(3, 0, embedded.size(3) / 2)),
               u3d::Error);
}

TEST(ControlNet, RejectsControlImageOfWrongSize) {
  ControlNetModel controlnet(ControlNetConfig::from_json(golden_config("controlnet"), "controlnet/config.json"),
                             torch::TensorOptions());
  EXPECT_THROW(controlnet->forward(torch::zeros({1, 4, 8, 8}), torch::tensor(1.0), torch::zeros({1, 1, 16}),
                                   torch::zeros({1, 3, 32, 32})),
               u3d::Error);
}

TEST(ControlNet, ConfigRejectsBgrConditioning) {
  auto json = golden_config("controlnet");
  json["controlnet_conditioning_channel_order"] = "bgr";
  EXPECT_THROW(ControlNetConfig::from_json(json, "controlnet/config.json"), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
