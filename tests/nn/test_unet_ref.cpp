// Unique3D's image2normal UNet: reference pass over the condition latents, then the main UNet with the
// pixel-wise reference attention on every attn1 (golden case unet_ref, reference weights = unet_base).
#include <gtest/gtest.h>

#include "golden.h"
#include "nn/models/unet_reference.h"
#include "nn/precision.h"
#include "required_skip.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

class UNetRef : public ::testing::Test {
 protected:
  void SetUp() override {
    config = UNetConfig::from_json(golden_config("unet_ref"), "unet_ref/config.json");
    model = std::make_unique<ReferenceUNet>(config, torch::TensorOptions());
    // The case's weights file is the main UNet without "ref_unet."; the reference is unet_base.
    load_golden_weights(*model->unet, "unet_ref", LoadPolicy{{"ref_unet.*"}, {}});
    load_golden_weights(*model->reference, "unet_base");
    in = golden_tensors("unet_ref", "inputs");
    ref = golden_tensors("unet_ref", "outputs");
  }
  UNetConfig config;
  std::unique_ptr<ReferenceUNet> model;
  TensorMap in, ref;
};

TEST_F(UNetRef, MatchesUnique3DForwardAndReferenceStates) {
  torch::NoGradGuard no_grad;
  TensorMap states;
  torch::Tensor out = model->forward(in["sample"], in["timestep"], in["encoder_hidden_states"], in["condition_latents"],
                                     &states);
  EXPECT_CLOSE_TO_GOLDEN(out, ref["sample_out"], kForwardTolerance);
  size_t recorded = 0;
  for (const auto& [key, expected] : ref) {
    if (!key.starts_with("ref.")) continue;
    SCOPED_TRACE(key);
    ASSERT_TRUE(states.count(key.substr(4)));
    EXPECT_CLOSE_TO_GOLDEN(states[key.substr(4)], expected, kForwardTolerance);
    ++recorded;
  }
  EXPECT_EQ(recorded, 4u);
  EXPECT_EQ(states.size(), recorded);
  EXPECT_TRUE(model->store->states.empty());  // every record consumed or cleared

  // The reference UNet itself is the plain UNet: its own (discarded) output matches too.
  EXPECT_CLOSE_TO_GOLDEN(model->reference->forward(in["condition_latents"], in["timestep"], in["encoder_hidden_states"]),
                         ref["internal.ref_unet_sample_out"], kForwardTolerance);
}

TEST_F(UNetRef, ParametersAreTheOfficialStateDictKeys) {
  size_t crosspond = 0, under_ref = 0;
  for (const auto& p : model->unet->named_parameters()) {
    crosspond += p.key().find(".attn1.processor.crosspond_attention.") != std::string::npos;
    under_ref += p.key().starts_with("ref_unet.");
  }
  EXPECT_EQ(crosspond, 4u * 8u);  // 4 attn1 modules x {to_q,to_k,to_v,to_out.0} x {weight,bias}
  EXPECT_EQ(under_ref, model->reference->named_parameters().size());
  for (const auto& p : model->reference->named_parameters()) EXPECT_EQ(p.key().find("crosspond"), std::string::npos);
}

TEST_F(UNetRef, GroupsOfSamplesShareOneCondition) {
  torch::NoGradGuard no_grad;
  // Two samples per condition (as classifier-free guidance or views do): each must equal a run with
  // the condition alone.
  torch::Tensor cond = in["condition_latents"].narrow(0, 0, 1);
  torch::Tensor context = in["encoder_hidden_states"].narrow(0, 0, 1);
  torch::Tensor joint = model->forward(in["sample"], in["timestep"], torch::cat({context, context}), cond);
  for (int64_t i = 0; i < 2; ++i) {
    torch::Tensor alone = model->forward(in["sample"].narrow(0, i, 1), in["timestep"], context, cond);
    EXPECT_LT(max_abs_diff(joint.narrow(0, i, 1), alone), 1e-5) << i;
  }
  // And a different condition changes the result.
  torch::Tensor other = model->forward(in["sample"].narrow(0, 0, 1), in["timestep"], context,
                                       in["condition_latents"].narrow(0, 1, 1));
  EXPECT_GT(max_abs_diff(joint.narrow(0, 0, 1), other), 1e-3);
}

TEST_F(UNetRef, Bf16StaysCloseToTheReference) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  set_precision(*model->unet, Precision::kBf16);  // converts the registered reference UNet too
  torch::Tensor out = model->forward(in["sample"], in["timestep"], in["encoder_hidden_states"], in["condition_latents"]);
  EXPECT_EQ(out.scalar_type(), torch::kFloat);
  EXPECT_RELATIVE_TO_GOLDEN(out, ref["sample_out"], 2e-2);
}

TEST_F(UNetRef, RejectsMismatchedConditionAndMissingReferencePass) {
  torch::NoGradGuard no_grad;
  EXPECT_THROW(model->forward(in["sample"], in["timestep"], in["encoder_hidden_states"],
                              torch::zeros({3, 4, 16, 16})),
               u3d::Error);
  EXPECT_THROW(model->forward(in["sample"], in["timestep"], in["encoder_hidden_states"],
                              torch::zeros({2, 4, 8, 8})),
               u3d::Error);
  // The main UNet alone has nothing to read.
  EXPECT_THROW(model->unet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"]), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
