#include "nn/layers/attention.h"

#include <gtest/gtest.h>

#include <cmath>

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
  // Two views at a time: entries {0,1} attend over 10 tokens together, as one batch entry would.
  auto joint = attn->forward(x, {}, 2);
  auto merged = attn->forward(x.reshape({2, 10, 8})).reshape({4, 5, 8});
  EXPECT_LT((joint - merged).abs().max().item<double>(), 1e-12);
  EXPECT_GT((joint - attn->forward(x)).abs().max().item<double>(), 1e-6);
}

}  // namespace
}  // namespace u3d::nn
