#include "nn/layers/attention.h"

#include <gtest/gtest.h>

#include <cmath>

#include "nn/layers/multiview_attention.h"
#include "nn/layers/transformer_2d.h"

namespace u3d::nn {
namespace {

// softmax(q·kᵀ/√d)·v per head, written out directly.
torch::Tensor naive_attention(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v, int64_t heads) {
  const int64_t b = q.size(0), d = q.size(2) / heads;
  auto split = [&](const torch::Tensor& x) { return x.reshape({b, x.size(1), heads, d}).permute({0, 2, 1, 3}); };
  auto scores = torch::matmul(split(q), split(k).transpose(-1, -2)) / std::sqrt(double(d));
  auto out = torch::matmul(scores.softmax(-1), split(v));
  return out.permute({0, 2, 1, 3}).reshape({b, q.size(1), heads * d});
}

TEST(Attention, ChunkedQueriesMatchDirectComputation) {
  torch::manual_seed(3);
  auto q = torch::randn({2, 37, 24}, torch::kDouble), k = torch::randn({2, 11, 24}, torch::kDouble),
       v = torch::randn({2, 11, 24}, torch::kDouble);
  auto expected = naive_attention(q, k, v, 3);
  const double scale = 1.0 / std::sqrt(8.0);
  // Budgets forcing one query per chunk, uneven chunks (last one shorter), and no chunking.
  for (int64_t budget : {int64_t{1}, int64_t{6 * 11 * 5}, kDefaultAttentionScoreBudget}) {
    auto out = multi_head_attention(q, k, v, 3, scale, budget);
    EXPECT_LT((out - expected).abs().max().item<double>(), 1e-12) << "budget " << budget;
  }
}

// Inputs whose GEGLU hidden layer would exceed 2^23 values go through the feed-forward in blocks of
// rows (here 131,072 rows of 64 hidden values, over the batch boundary); the result is the one-block formula.
TEST(Attention, FeedForwardInRowBlocksMatchesWholeInput) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(5);
  FeedForward ff(8, torch::TensorOptions());
  randomize_parameters(*ff, 0.5);
  const torch::Tensor x = torch::randn({3, 100000, 8});
  const torch::Tensor whole = ff->proj_out->forward(ff->geglu->forward(x));
  // fp32 sums in a different order for the blocks than for the whole (the kernels block by shape).
  EXPECT_LE((ff->forward(x) - whole).abs().max().item<double>(), 2e-5);
}

TEST(Attention, MultiViewJoinsConsecutiveBatchEntries) {
  torch::manual_seed(4);
  AttentionOptions o;
  o.query_dim = 8;
  o.heads = 2;
  o.dim_head = 4;
  Attention attn(o, torch::TensorOptions().dtype(torch::kDouble));
  for (auto& p : attn->parameters()) p.data().normal_();
  torch::NoGradGuard no_grad;
  auto x = torch::randn({4, 5, 8}, torch::kDouble);
  auto plain = attn->forward(x);
  auto merged = attn->forward(x.reshape({2, 10, 8})).reshape({4, 5, 8});
  // Two views at a time: entries {0,1} attend over 10 tokens together, as one batch entry would.
  attn->set_processor(std::make_shared<MultiViewAttentionProcessor>(2));
  auto joint = attn->forward(x);
  EXPECT_LT((joint - merged).abs().max().item<double>(), 1e-12);
  EXPECT_GT((joint - plain).abs().max().item<double>(), 1e-6);
  EXPECT_THROW(attn->forward(x.narrow(0, 0, 3)), c10::Error);
}

// A model whose attention modules sit where the UNet's transformer blocks put theirs.
struct TwoBlocksImpl : torch::nn::Module {
  TwoBlocksImpl() {
    AttentionOptions o;
    o.query_dim = 8;
    o.heads = 2;
    o.dim_head = 4;
    for (const char* block : {"a", "b"}) {
      auto holder = register_module(block, std::make_shared<torch::nn::Module>());
      holder->register_module("attn1", Attention(o, torch::TensorOptions()));
      holder->register_module("attn2", Attention(o, torch::TensorOptions()));
    }
  }
};

TEST(Attention, ProcessorsGoWhereTheChooserSays) {
  TwoBlocksImpl model;
  auto multiview = std::make_shared<MultiViewAttentionProcessor>(2);
  EXPECT_EQ(set_attention_processors(model, self_attention_only(multiview)), 2u);
  for (const auto& item : model.named_modules("", false)) {
    auto* attention = dynamic_cast<AttentionImpl*>(item.value().get());
    if (!attention) continue;
    const bool self_attention = item.key().ends_with(".attn1");
    EXPECT_EQ(attention->processor == multiview, self_attention) << item.key();
    if (!self_attention) {
      EXPECT_NE(std::dynamic_pointer_cast<PlainAttentionProcessor>(attention->processor), nullptr);
    }
  }
  // The processor is the submodule "processor"; this one adds no parameters (to_q, to_k, to_v, to_out.0
  // weight and bias in each of the four modules).
  EXPECT_EQ(model.named_modules("", false).find("a.attn1.processor")->get(), multiview.get());
  EXPECT_EQ(model.named_parameters().size(), 4u * 5u);
}

}  // namespace
}  // namespace u3d::nn
