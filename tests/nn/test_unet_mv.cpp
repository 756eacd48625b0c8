// Unique3D's image2mvimage UNet: class embedding, cat_condition (8 conv_in channels) and joint
// multi-view self-attention over the 4 views.
#include <gtest/gtest.h>

#include "golden.h"
#include "nn/layers/multiview_attention.h"
#include "nn/models/unet.h"
#include "nn/preprocess/pil_resize.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

TEST(UNetMultiView, MatchesUnique3DForward) {
  torch::NoGradGuard no_grad;
  auto config = UNetConfig::from_json(golden_config("unet_mv"), "unet_mv/config.json");
  EXPECT_EQ(config.num_class_embeds, 8);
  UNet2DConditionModel unet(config, torch::TensorOptions());
  load_golden_weights(*unet, "unet_mv");
  auto in = golden_tensors("unet_mv", "inputs");
  auto ref = golden_tensors("unet_mv", "outputs");

  // The attn1 of every transformer block (each has one attn2) takes the multi-view processor.
  size_t transformer_blocks = 0;
  for (const auto& item : unet->named_modules("", false)) transformer_blocks += item.key().ends_with(".attn2");
  EXPECT_GT(transformer_blocks, 0u);
  EXPECT_EQ(set_attention_processors(*unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(4))),
            transformer_blocks);
  TensorMap trace;
  UNetExtras extras;
  extras.class_labels = in["class_labels"];
  extras.condition_latents = in["condition_latents"];
  extras.trace = &trace;
  torch::Tensor out = unet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"], extras);
  EXPECT_CLOSE_TO_GOLDEN(trace["conv_in_input"], ref["internal.conv_in_input"], 0.0);
  EXPECT_CLOSE_TO_GOLDEN(out, ref["sample_out"], kForwardTolerance);

  // Without the joint attention the result must differ: the test sees the multi-view path.
  set_attention_processors(*unet, self_attention_only(std::make_shared<PlainAttentionProcessor>()));
  EXPECT_GT(max_abs_diff(unet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"], extras),
                         ref["sample_out"]),
            1e-3);
}

TEST(UNetMultiView, RequiresClassLabels) {
  torch::NoGradGuard no_grad;
  auto config = UNetConfig::from_json(golden_config("unet_mv"), "unet_mv/config.json");
  UNet2DConditionModel unet(config, torch::TensorOptions());
  UNetExtras extras;
  extras.condition_latents = torch::zeros({1, 4, 16, 16});
  EXPECT_THROW(unet->forward(torch::zeros({4, 4, 16, 16}), torch::tensor(1.0), torch::zeros({4, 1, 16}), extras),
               u3d::Error);
}

// VaeImageProcessor resizes with PIL LANCZOS, then maps uint8 to [-1, 1]; one uint8 step is 2/255, so
// agreement to 1e-6 means the resized bytes are identical.
TEST(PilResize, LanczosMatchesVaeImageProcessor) {
  auto in = golden_tensors("unet_mv", "inputs");
  auto ref = golden_tensors("unet_mv", "outputs");
  torch::Tensor resized = pil_resize(in["pipe.test_image_uint8"], 32, 32, PilFilter::Lanczos);
  torch::Tensor x = (resized.to(torch::kFloat) / 255.0f * 2.0f - 1.0f).permute({2, 0, 1}).unsqueeze(0);
  EXPECT_CLOSE_TO_GOLDEN(x, ref["pipe.vae_preprocessed"], 1e-6);
}

}  // namespace
}  // namespace u3d::nn
