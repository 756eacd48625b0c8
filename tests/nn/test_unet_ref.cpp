// Unique3D's image2normal UNet: reference pass over the condition latents, then the main UNet with the
// pixel-wise reference attention on every attn1 (golden case unet_ref, reference weights = unet_base).
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

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

// Records the batch size of every call, by module name, and attends as usual.
class CountingProcessor : public PlainAttentionProcessor {
 public:
  CountingProcessor(std::map<std::string, std::vector<int64_t>>& calls, std::string name)
      : calls_(calls), name_(std::move(name)) {}
  torch::Tensor process(AttentionImpl& attention, const torch::Tensor& x, const torch::Tensor& context) override {
    calls_[name_].push_back(x.size(0));
    return PlainAttentionProcessor::process(attention, x, context);
  }

 private:
  std::map<std::string, std::vector<int64_t>>& calls_;
  std::string name_;
};

// Counts the calls of every cross-attention (attn2) of the reference UNet, which the reference attention
// leaves alone: they show how far the reference pass ran and on how many samples.
std::map<std::string, std::vector<int64_t>>& count_reference_cross_attention(ReferenceUNet& model) {
  static std::map<std::string, std::vector<int64_t>> calls;
  calls.clear();
  set_attention_processors(*model.reference, [](const std::string& name, const AttentionImpl&)
                                                  -> std::shared_ptr<AttentionProcessor> {
    if (!name.ends_with(".attn2")) return nullptr;
    calls[name];
    return std::make_shared<CountingProcessor>(calls, name);
  });
  return calls;
}

// The batch sizes of the counted modules that ran, each call in turn (a module that did not run is left out).
std::vector<int64_t> batches_run(std::map<std::string, std::vector<int64_t>>& calls) {
  std::vector<int64_t> all;
  for (auto& [name, batches] : calls) {
    all.insert(all.end(), batches.begin(), batches.end());
    batches.clear();
  }
  return all;
}

// The reference pass stops at the last attn1 input it records: the last transformer block's
// cross-attention (and all after it) never runs, every other one runs once; called alone, the
// reference UNet still runs whole.
TEST_F(UNetRef, ReferencePassStopsAtItsLastRecord) {
  torch::NoGradGuard no_grad;
  auto& calls = count_reference_cross_attention(*model);
  ASSERT_EQ(calls.size(), 4u);
  const std::string last = "up_blocks.1.attentions.1.transformer_blocks.0.attn2";
  ASSERT_TRUE(calls.count(last));
  TensorMap states;
  torch::Tensor out = model->forward(in["sample"], in["timestep"], in["encoder_hidden_states"], in["condition_latents"],
                                     &states);
  EXPECT_CLOSE_TO_GOLDEN(out, ref["sample_out"], kForwardTolerance);
  EXPECT_EQ(states.size(), 4u);
  for (const auto& [name, batches] : calls) EXPECT_EQ(batches.size(), name == last ? 0u : 1u) << name;
  for (auto& [name, batches] : calls) batches.clear();
  model->reference->forward(in["condition_latents"], in["timestep"], in["encoder_hidden_states"]);
  for (const auto& [name, batches] : calls) EXPECT_EQ(batches.size(), 1u) << name;
  model->store->states.clear();
}

// Groups with identical condition latents, context and timestep share one reference pass (as the
// unconditional half of guidance, where every view has zeros): the pass runs on the distinct groups
// only, and every group reads exactly the tokens a pass over the distinct groups records.
TEST_F(UNetRef, IdenticalGroupsShareOneReferencePass) {
  torch::NoGradGuard no_grad;
  auto& calls = count_reference_cross_attention(*model);
  const torch::Tensor cond = in["condition_latents"], context = in["encoder_hidden_states"];
  ASSERT_EQ(cond.size(0), 2);
  TensorMap distinct_states;
  model->forward(in["sample"], in["timestep"], context, cond, &distinct_states);
  // Three of the four cross-attentions run (ReferencePassStopsAtItsLastRecord), on both groups.
  const std::vector<int64_t> two_groups{2, 2, 2};
  EXPECT_EQ(batches_run(calls), two_groups);

  const torch::Tensor order = torch::tensor({0, 1, 0, 0}, torch::kLong);
  const torch::Tensor sample = torch::cat({in["sample"], in["sample"]});
  TensorMap states;
  torch::Tensor out = model->forward(sample, in["timestep"], context.index_select(0, order),
                                     cond.index_select(0, order), &states);
  EXPECT_EQ(batches_run(calls), two_groups);
  ASSERT_EQ(states.size(), distinct_states.size());
  for (const auto& [name, tokens] : states) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(torch::equal(tokens, distinct_states[name].index_select(0, order)));
  }
  // Each sample's output is that of its own condition, as when the groups differ.
  torch::Tensor alone = model->forward(sample.narrow(0, 3, 1), in["timestep"], context.narrow(0, 0, 1),
                                       cond.narrow(0, 0, 1));
  EXPECT_LT(max_abs_diff(out.narrow(0, 3, 1), alone), 1e-5);
  batches_run(calls);

  // Four identical groups: one pass of one sample.
  model->forward(sample, in["timestep"], context.narrow(0, 0, 1).repeat({4, 1, 1}),
                 cond.narrow(0, 0, 1).repeat({4, 1, 1, 1}));
  EXPECT_EQ(batches_run(calls), (std::vector<int64_t>{1, 1, 1}));
  // -0 and +0 are not the same input: no sharing then (the tokens may differ in the sign of a zero).
  const torch::Tensor zeros = torch::zeros_like(cond.narrow(0, 0, 1));
  model->forward(in["sample"], in["timestep"], context.narrow(0, 0, 1).repeat({2, 1, 1}), torch::cat({zeros, zeros.neg()}));
  EXPECT_EQ(batches_run(calls), two_groups);
  // Nor are groups at different timesteps.
  model->forward(in["sample"], torch::tensor({10.0f, 20.0f}), context.narrow(0, 0, 1).repeat({2, 1, 1}),
                 cond.narrow(0, 0, 1).repeat({2, 1, 1, 1}));
  EXPECT_EQ(batches_run(calls), two_groups);
}

// Groups that share one reference entry have its crosspond term (to_out(to_v(tokens))) computed once for
// all of them (ReferenceStore::rows). Their outputs are those of groups with an entry each, bit for bit:
// +0 and -0 condition latents are the same values but not the same input, so those are not shared.
TEST_F(UNetRef, SharedReferenceEntriesGiveTheValuesOfSeparateOnes) {
  torch::NoGradGuard no_grad;
  auto& calls = count_reference_cross_attention(*model);
  const torch::Tensor zeros = torch::zeros_like(in["condition_latents"].narrow(0, 0, 1));
  const torch::Tensor sample = torch::cat({in["sample"], in["sample"].flip(0)});
  const torch::Tensor context = in["encoder_hidden_states"].narrow(0, 0, 1).repeat({4, 1, 1});
  for (const int64_t groups : {2, 4}) {
    SCOPED_TRACE(testing::Message() << groups << " groups of " << 4 / groups);
    torch::Tensor same = zeros.repeat({groups, 1, 1, 1}), signs = same.clone();
    signs.narrow(0, 1, 1).neg_();
    const torch::Tensor shared = model->forward(sample, in["timestep"], context, same);
    EXPECT_EQ(batches_run(calls), (std::vector<int64_t>{1, 1, 1}));
    const torch::Tensor separate = model->forward(sample, in["timestep"], context, signs);
    EXPECT_EQ(batches_run(calls).front(), 2);
    EXPECT_TRUE(torch::equal(shared, separate));
  }
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
