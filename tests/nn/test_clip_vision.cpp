#include "nn/models/clip_vision.h"

#include <gtest/gtest.h>

#include "core/image.h"
#include "golden.h"
#include "nn/preprocess/clip_image_processor.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

TEST(ClipVision, MatchesTransformersForward) {
  torch::NoGradGuard no_grad;
  auto config = ClipVisionConfig::from_json(golden_config("clip_vision"), "clip_vision/config.json");
  ClipVisionModelWithProjection model(config, torch::TensorOptions());
  load_golden_weights(*model, "clip_vision", clip_policy());
  auto in = golden_tensors("clip_vision", "inputs");
  auto ref = golden_tensors("clip_vision", "outputs");

  ClipVisionOutput out = model->forward(in["pixel_values"], true);
  EXPECT_CLOSE_TO_GOLDEN(out.image_embeds, ref["image_embeds"], kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(out.last_hidden_state, ref["last_hidden_state"], kForwardTolerance);
  ASSERT_EQ(out.hidden_states.size(), 3u);
  for (size_t i = 0; i < out.hidden_states.size(); ++i)
    EXPECT_CLOSE_TO_GOLDEN(out.hidden_states[i], ref["hidden_states." + std::to_string(i)], kForwardTolerance);
}

TEST(ClipVision, RejectsWrongInputSize) {
  auto config = ClipVisionConfig::from_json(golden_config("clip_vision"), "clip_vision/config.json");
  ClipVisionModelWithProjection model(config, torch::TensorOptions());
  EXPECT_THROW(model->forward(torch::zeros({1, 3, 224, 224})), u3d::Error);
}

// OpenCLIP's ViT-H/14 (the IP-Adapter image encoder) says "hidden_act": "gelu": the exact erf GELU.
TEST(ClipVision, GeluConfigUsesTheExactGelu) {
  torch::NoGradGuard no_grad;
  auto json = golden_config("clip_vision");
  json["hidden_act"] = "gelu";
  auto config = ClipVisionConfig::from_json(json, "vit-h");
  EXPECT_EQ(config.hidden_act, ClipActivation::kGelu);
  ClipVisionModelWithProjection model(config, torch::TensorOptions());
  load_golden_weights(*model, "clip_vision", clip_policy());
  auto& mlp = model->layers[0]->mlp;
  const torch::Tensor x = torch::randn({2, 5, config.hidden_size});
  EXPECT_TRUE(torch::allclose(mlp->forward(x), mlp->fc2->forward(torch::gelu(mlp->fc1->forward(x)))));
  json["hidden_act"] = "relu";
  EXPECT_THROW(ClipVisionConfig::from_json(json, "vit-h"), u3d::Error);
}

TEST(ClipImageProcessor, BicubicCropIsBitExactWithPillow) {
  auto config = ClipImageProcessorConfig::from_json(golden_config("clip_vision", "preprocessor_config.json"),
                                                    "preprocessor_config.json");
  ClipImageProcessor processor(config);
  auto in = golden_tensors("clip_vision", "inputs");
  auto ref = golden_tensors("clip_vision", "outputs");
  torch::Tensor cropped = processor.resize_and_crop(in["test_image_uint8"]);
  ASSERT_EQ(cropped.sizes(), ref["processor.cropped_uint8"].sizes());
  const int64_t mismatches = (cropped != ref["processor.cropped_uint8"]).sum().item<int64_t>();
  EXPECT_EQ(mismatches, 0) << "of " << cropped.numel() << " bytes differ from PIL";
  EXPECT_CLOSE_TO_GOLDEN(processor.pixel_values(in["test_image_uint8"]), ref["processor.pixel_values"], 1e-6);
}

TEST(ClipImageProcessor, Tiny32VariantFromPng) {
  auto config = ClipImageProcessorConfig::from_json(golden_config("clip_vision", "preprocessor_config_tiny32.json"),
                                                    "preprocessor_config_tiny32.json");
  EXPECT_EQ(config.shortest_edge, 32);
  ClipImageProcessor processor(config);
  // Through the PNG loader, to check the float -> uint8 path gives PIL's bytes back.
  torch::Tensor rgb = image_to_uint8_rgb(load_image(golden_dir("clip_vision") / "test_image_64x48.png"));
  auto in = golden_tensors("clip_vision", "inputs");
  EXPECT_TRUE(torch::equal(rgb, in["test_image_uint8"]));
  auto ref = golden_tensors("clip_vision", "outputs");
  EXPECT_CLOSE_TO_GOLDEN(processor.pixel_values(rgb), ref["processor_tiny32.pixel_values"], 1e-6);
}

TEST(ClipImageProcessor, RejectsNonRgbInput) {
  ClipImageProcessor processor{ClipImageProcessorConfig{}};
  EXPECT_THROW(processor.pixel_values(torch::zeros({8, 8, 4}, torch::kUInt8)), u3d::Error);
  EXPECT_THROW(processor.pixel_values(torch::zeros({8, 8, 3}, torch::kFloat)), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
