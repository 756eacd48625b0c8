#include "nn/layers/attention.h"

#include <gtest/gtest.h>

#include <cmath>

#include "golden.h"
#include "nn/layers/attention_kernel.h"
#include "nn/layers/multiview_attention.h"
#include "nn/layers/transformer_2d.h"

namespace u3d::nn {
namespace {

using u3d::nn::test::relative_error;

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

// The fused fp32 kernel (nn/layers/attention_kernel.h) against float64 on the same values: lengths that
// are not multiples of its tiles (32 queries, 64 keys, 8 keys a register block), one key, the head
// sizes of the models (40, 64, 80, 160), scores up to several hundred (the online softmax rescales its
// sums many times), a key tensor that is a strided view. multi_head_attention takes this path.
TEST(Attention, FusedKernelMatchesFloat64) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(6);
  struct Case {
    int64_t batch, queries, keys, heads, dim;
    double magnitude;  // of q and k
  };
  for (const Case& c : {Case{2, 37, 11, 3, 8, 1.0}, Case{1, 100, 77, 2, 40, 1.0}, Case{2, 33, 257, 5, 64, 1.0},
                        Case{1, 70, 130, 1, 80, 3.0}, Case{1, 31, 65, 2, 160, 1.0}, Case{1, 64, 1, 1, 40, 1.0},
                        Case{2, 300, 1000, 2, 40, 10.0}}) {
    SCOPED_TRACE(testing::Message() << c.batch << " x " << c.queries << " queries, " << c.keys << " keys, " << c.heads
                                    << " heads of " << c.dim << ", magnitude " << c.magnitude);
    const int64_t channels = c.heads * c.dim;
    const torch::Tensor q = torch::randn({c.batch, c.queries, channels}) * c.magnitude;
    const torch::Tensor k = (torch::randn({c.batch, c.keys, 2 * channels}) * c.magnitude).narrow(2, channels, channels);
    const torch::Tensor v = torch::randn({c.batch, c.keys, channels});
    ASSERT_TRUE(fused_attention_applies(q, k, v, c.heads));
    const double scale = 1.0 / std::sqrt(double(c.dim));
    const torch::Tensor out = fused_attention(q, k, v, c.heads, scale);
    EXPECT_EQ(out.scalar_type(), torch::kFloat);
    const torch::Tensor expected = naive_attention(q.to(torch::kDouble), k.to(torch::kDouble), v.to(torch::kDouble), c.heads);
    // fp32 products and sums; the scores' own rounding grows with their magnitude (|s| * 2^-24 of phase).
    EXPECT_LT(relative_error(out.to(torch::kDouble), expected), 1e-5);
    EXPECT_LT((out.to(torch::kDouble) - expected).abs().max().item<double>(), 1e-6 * (1 + c.magnitude * c.magnitude * c.dim));
    EXPECT_TRUE(torch::equal(multi_head_attention(q, k, v, c.heads, scale), out));
  }
  // What the kernel does not take goes the blocked way: float64, heads of 12 channels.
  const torch::Tensor x = torch::randn({1, 5, 24});
  EXPECT_FALSE(fused_attention_applies(x.to(torch::kDouble), x.to(torch::kDouble), x.to(torch::kDouble), 3));
  EXPECT_FALSE(fused_attention_applies(x, x, x, 2));
  EXPECT_TRUE(fused_attention_applies(x, x, x, 3));
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
