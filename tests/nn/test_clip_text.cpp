#include "nn/models/clip_text.h"

#include <gtest/gtest.h>

#include "golden.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

TEST(ClipText, MatchesTransformersForward) {
  torch::NoGradGuard no_grad;
  const auto config = ClipTextConfig::from_json(golden_config("clip_text"), "clip_text/config.json");
  EXPECT_EQ(config.eos_token_id, 2);
  ClipTextModel model(config, torch::TensorOptions());
  load_golden_weights(*model, "clip_text", clip_policy());
  auto in = golden_tensors("clip_text", "inputs");
  auto ref = golden_tensors("clip_text", "outputs");

  ClipTextOutput out = model->forward(in["input_ids"], true);
  EXPECT_CLOSE_TO_GOLDEN(out.last_hidden_state, ref["last_hidden_state"], kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(out.pooler_output, ref["pooler_output"], kForwardTolerance);
  ASSERT_EQ(out.hidden_states.size(), 3u);
  for (size_t i = 0; i < out.hidden_states.size(); ++i)
    EXPECT_CLOSE_TO_GOLDEN(out.hidden_states[i], ref["hidden_states." + std::to_string(i)], kForwardTolerance);
}

// With a non-legacy eos_token_id the pooled token is the first position holding that id, not the
// largest id: ids padded with eos 999 but pooled at eos 5 pick another position.
TEST(ClipText, PoolsAtFirstEosTokenIdUnlessLegacy) {
  torch::NoGradGuard no_grad;
  auto json = golden_config("clip_text");
  json["eos_token_id"] = 5;
  ClipTextModel model(ClipTextConfig::from_json(json, "clip_text/config.json"), torch::TensorOptions());
  load_golden_weights(*model, "clip_text", clip_policy());
  const torch::Tensor ids = torch::tensor({998, 7, 5, 3, 999, 999}, torch::kLong).unsqueeze(0);
  ClipTextOutput out = model->forward(ids);
  EXPECT_TRUE(torch::equal(out.pooler_output[0], out.last_hidden_state[0][2]));
}

TEST(ClipText, RejectsBadIds) {
  ClipTextModel model(ClipTextConfig::from_json(golden_config("clip_text"), "clip_text/config.json"),
                      torch::TensorOptions());
  EXPECT_THROW(model->forward(torch::zeros({1, 78}, torch::kLong)), u3d::Error);
  EXPECT_THROW(model->forward(torch::full({1, 5}, 1000, torch::kLong)), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
