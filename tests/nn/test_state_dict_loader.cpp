#include "nn/checkpoint/state_dict_loader.h"

#include <gtest/gtest.h>

#include "core/error.h"

using namespace u3d::nn;

namespace {

// A miniature VAE-like module: a conv, a Linear attention projection and an integer buffer.
struct TinyAttention : torch::nn::Module {
  TinyAttention() {
    to_q = register_module("to_q", torch::nn::Linear(4, 4));
    to_out = register_module("to_out", torch::nn::ModuleList(torch::nn::Linear(4, 4)));
  }
  torch::nn::Linear to_q{nullptr};
  torch::nn::ModuleList to_out{nullptr};
};

struct TinyModel : torch::nn::Module {
  TinyModel() {
    conv = register_module("conv", torch::nn::Conv2d(torch::nn::Conv2dOptions(2, 3, 3)));
    attn = register_module("attn", std::make_shared<TinyAttention>());
    steps = register_buffer("steps", torch::zeros({2}, torch::kInt64));
  }
  torch::nn::Conv2d conv{nullptr};
  std::shared_ptr<TinyAttention> attn;
  torch::Tensor steps;
};

TensorMap full_checkpoint() {
  return {{"conv.weight", torch::randn({3, 2, 3, 3})},      {"conv.bias", torch::randn({3})},
          {"attn.to_q.weight", torch::randn({4, 4})},       {"attn.to_q.bias", torch::randn({4})},
          {"attn.to_out.0.weight", torch::randn({4, 4})},   {"attn.to_out.0.bias", torch::randn({4})},
          {"steps", torch::tensor({int64_t(5), int64_t(6)})}};
}

std::string load_error(TinyModel& model, const TensorMap& weights, const LoadPolicy& policy = {}) {
  try {
    load_state_dict(model, weights, policy, "tiny.safetensors");
  } catch (const u3d::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(StateDictLoader, CopiesEveryTensor) {
  TinyModel model;
  const TensorMap w = full_checkpoint();
  const LoadReport report = load_state_dict(model, w, {}, "tiny.safetensors");
  EXPECT_EQ(report.loaded, 7);
  EXPECT_TRUE(report.converted.empty());
  EXPECT_TRUE(torch::equal(model.conv->weight, w.at("conv.weight")));
  EXPECT_TRUE(torch::equal(model.attn->to_out[0]->as<torch::nn::Linear>()->bias, w.at("attn.to_out.0.bias")));
  EXPECT_TRUE(torch::equal(model.steps, w.at("steps")));
  EXPECT_FALSE(model.conv->weight.grad().defined());
}

TEST(StateDictLoader, ConvertsFloatingDtypesAndReportsIt) {
  TinyModel model;
  TensorMap w = full_checkpoint();
  w["conv.weight"] = w["conv.weight"].to(torch::kBFloat16);
  w["conv.bias"] = w["conv.bias"].to(torch::kFloat16);
  const LoadReport report = load_state_dict(model, w, {}, "tiny.safetensors");
  EXPECT_EQ(report.converted.size(), 2u);
  EXPECT_EQ(model.conv->weight.scalar_type(), torch::kFloat32);
  EXPECT_TRUE(torch::equal(model.conv->weight, w["conv.weight"].to(torch::kFloat32)));
}

TEST(StateDictLoader, MismatchesAreOneErrorNamingEachTensor) {
  TinyModel model;
  const torch::Tensor before = model.conv->weight.clone();
  TensorMap w = full_checkpoint();
  w.erase("attn.to_q.bias");
  w["conv.weight"] = torch::randn({3, 4, 3, 3});
  w["steps"] = torch::rand({2});
  w["extra.weight"] = torch::randn({1});
  const std::string msg = load_error(model, w);
  for (const char* fragment : {"tiny.safetensors", "missing tensors (1)", "attn.to_q.bias", "unexpected tensors (1)",
                               "extra.weight", "shape mismatches (1)", "conv.weight: file [3, 4, 3, 3], model [3, 2, 3, 3]",
                               "wrong dtypes (1)", "steps: file Float, model Long"}) {
    EXPECT_NE(msg.find(fragment), std::string::npos) << "'" << fragment << "' not in: " << msg;
  }
  EXPECT_TRUE(torch::equal(model.conv->weight, before)) << "nothing may be copied when the check fails";
}

TEST(StateDictLoader, PolicyAllowsDeclaredAbsentAndExtraKeys) {
  TinyModel model;
  TensorMap w = full_checkpoint();
  w.erase("steps");
  w["vision_model.embeddings.position_ids"] = torch::arange(4).view({1, 4});
  EXPECT_NE(load_error(model, w), "");
  LoadPolicy policy = clip_policy();
  policy.may_be_missing.push_back("step*");
  const LoadReport report = load_state_dict(model, w, policy, "tiny.safetensors");
  EXPECT_EQ(report.missing_allowed, std::vector<std::string>{"steps"});
  EXPECT_EQ(report.ignored, std::vector<std::string>{"vision_model.embeddings.position_ids"});
}

TEST(StateDictLoader, LegacyAttentionNamesAndConvShapedWeights) {
  TinyModel model;
  TensorMap w = full_checkpoint();
  const torch::Tensor q = torch::randn({4, 4, 1, 1});
  const torch::Tensor out = torch::randn({4, 4});
  w.erase("attn.to_q.weight");
  w.erase("attn.to_out.0.weight");
  w["attn.query.weight"] = q;
  w["attn.proj_attn.weight"] = out;
  const LoadReport report = load_state_dict(model, w, {}, "vae.bin");
  EXPECT_EQ(report.renamed.size(), 2u);
  EXPECT_TRUE(torch::equal(model.attn->to_q->weight, q.view({4, 4})));
  EXPECT_TRUE(torch::equal(model.attn->to_out[0]->as<torch::nn::Linear>()->weight, out));

  w["attn.to_q.weight"] = q.view({4, 4});  // both names at once is ambiguous
  const std::string msg = load_error(model, w);
  EXPECT_NE(msg.find("given twice"), std::string::npos) << msg;
}

TEST(StateDictLoader, TakePrefixSplitsTheReferenceUnet) {
  TensorMap w = {{"conv_in.weight", torch::zeros({1})},
                 {"ref_unet.conv_in.weight", torch::ones({1})},
                 {"ref_unet.conv_out.bias", torch::ones({2})}};
  const TensorMap ref = take_prefix(w, kRefUnetPrefix);
  EXPECT_EQ(ref.size(), 2u);
  EXPECT_TRUE(ref.count("conv_in.weight") && ref.count("conv_out.bias"));
  EXPECT_EQ(w.size(), 1u);
  EXPECT_TRUE(take_prefix(w, kRefUnetPrefix).empty());
}

TEST(StateDictLoader, GlobMatching) {
  EXPECT_TRUE(key_matches("*.embeddings.position_ids", "text_model.embeddings.position_ids"));
  EXPECT_TRUE(key_matches("ref_unet.*", "ref_unet.a.b"));
  EXPECT_TRUE(key_matches("*attn1*crosspond*", "down.attn1.processor.crosspond_attention.to_q.weight"));
  EXPECT_FALSE(key_matches("ref_unet.*", "unet.ref"));
  EXPECT_FALSE(key_matches("a*b", "a.c"));
  EXPECT_TRUE(key_matches("exact", "exact"));
}
