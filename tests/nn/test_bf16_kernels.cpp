// The bf16 CPU kernels behind Conv2d, GroupNorm, the attention softmax (nn/layers/onednn_conv.h,
// nn/layers/group_norm_kernel.h, nn/layers/softmax_kernel.h), the fused attention (nn/layers/attention_kernel.h),
// GEGLU (nn/layers/geglu_kernel.h) and LayerNorm (nn/layers/layer_norm_kernel.h), against ATen in fp32 or float64 on the same bf16 values; and the
// fp32 path of the convolution and GroupNorm kernels against float64 (Fp32Kernels).
#include <ATen/Parallel.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "golden.h"
#include "nn/layers/attention.h"
#include "nn/layers/attention_kernel.h"
#include "nn/layers/geglu_kernel.h"
#include "nn/layers/group_norm_kernel.h"
#include "nn/layers/layer_norm_kernel.h"
#include "nn/layers/layers.h"
#include "nn/layers/onednn_conv.h"
#include "nn/layers/softmax_kernel.h"
#include "nn/precision.h"
#include "required_skip.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

// Whether every element of `actual` (bf16) is `expected` (fp32) rounded to bf16, give or take one unit
// in the last place of bf16 (2^-8 relative) where the fp32 statistics or sums differ in their last bits.
::testing::AssertionResult within_one_bf16_step(const torch::Tensor& actual, const torch::Tensor& expected) {
  const torch::Tensor a = actual.to(torch::kFloat), e = expected.to(torch::kFloat);
  const torch::Tensor bound = e.abs() * (1.0 / 128) + 1e-30;
  const torch::Tensor excess = (a - e).abs() - bound;
  const double worst = excess.max().item<double>();
  if (worst <= 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "largest excess over one bf16 step: " << worst;
}

struct ConvCase {
  int64_t batch, in, out, height, width, kernel, stride, padding;
  bool bias;
};

// The shapes both precisions' convolutions are tested on.
constexpr ConvCase kConvCases[] = {
    {2, 8, 16, 9, 7, 3, 1, 1, true},    // odd sizes
    {1, 16, 8, 12, 10, 3, 2, 1, true},  // a downsampler
    {3, 24, 40, 5, 6, 1, 1, 0, false},  // 1x1, no bias
    {8, 64, 32, 4, 4, 3, 1, 1, true},   // 16 output pixels: the direct kernel
    {2, 4, 8, 1, 1, 3, 1, 1, true},     // one pixel
};

testing::Message describe(const ConvCase& c) {
  return testing::Message() << c.batch << "x" << c.in << "x" << c.height << "x" << c.width << " -> " << c.out << " k"
                            << c.kernel << " s" << c.stride;
}

TEST(Bf16Kernels, ConvolutionMatchesFp32OnTheSameValues) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  torch::manual_seed(11);
  for (const ConvCase& c : kConvCases) {
    SCOPED_TRACE(describe(c));
    Conv2d conv(c.in, c.out, c.kernel, c.stride, c.padding, c.bias, torch::TensorOptions());
    randomize_parameters(*conv, 0.2);
    set_precision(*conv, Precision::kBf16);
    const torch::Tensor x = torch::randn({c.batch, c.in, c.height, c.width}).to(torch::kBFloat16);
    const torch::Tensor y = conv->forward(x);
    EXPECT_EQ(y.scalar_type(), torch::kBFloat16);
    EXPECT_TRUE(y.is_contiguous(at::MemoryFormat::ChannelsLast));
    const torch::Tensor bias = c.bias ? conv->bias.to(torch::kFloat) : torch::Tensor();
    const torch::Tensor expected = torch::conv2d(x.to(torch::kFloat), conv->weight.to(torch::kFloat), bias,
                                                 {c.stride, c.stride}, {c.padding, c.padding});
    ASSERT_EQ(y.sizes(), expected.sizes());
    // fp32 sums of bf16 products, one rounding at the end.
    EXPECT_LT(relative_error(y.to(torch::kFloat), expected), 4e-3);
    // A channels-last input takes the same path and gives the same values.
    EXPECT_TRUE(torch::equal(conv->forward(x.contiguous(at::MemoryFormat::ChannelsLast)), y));
  }
}

TEST(Bf16Kernels, ConvolutionFollowsWeightsChangedAfterTheFirstCall) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  torch::manual_seed(12);
  Conv2d conv(8, 8, 3, 1, 1, true, torch::TensorOptions());
  randomize_parameters(*conv, 0.2);
  set_precision(*conv, Precision::kBf16);
  const torch::Tensor x = torch::randn({2, 8, 6, 6}).to(torch::kBFloat16);
  const auto reference = [&] {
    return torch::conv2d(x.to(torch::kFloat), conv->weight.to(torch::kFloat), conv->bias.to(torch::kFloat), {1, 1},
                         {1, 1});
  };
  const torch::Tensor first = conv->forward(x);
  EXPECT_LT(relative_error(first.to(torch::kFloat), reference()), 4e-3);
  // Modified in place (as a weight loader's copy_ does): the packed copy is rebuilt.
  conv->weight.neg_();
  EXPECT_LT(relative_error(conv->forward(x).to(torch::kFloat), reference()), 4e-3);
  // Replaced by another tensor.
  conv->weight.set_data(torch::randn({8, 8, 3, 3}).to(torch::kBFloat16));
  EXPECT_LT(relative_error(conv->forward(x).to(torch::kFloat), reference()), 4e-3);
  // A second input size gets its own plan, and the first one still answers.
  const torch::Tensor larger = torch::randn({1, 8, 11, 5}).to(torch::kBFloat16);
  const torch::Tensor y = conv->forward(larger);
  EXPECT_LT(relative_error(y.to(torch::kFloat), torch::conv2d(larger.to(torch::kFloat), conv->weight.to(torch::kFloat),
                                                              conv->bias.to(torch::kFloat), {1, 1}, {1, 1})),
            4e-3);
  EXPECT_LT(relative_error(conv->forward(x).to(torch::kFloat), reference()), 4e-3);
}

TEST(Bf16Kernels, ConvolutionPackedInPlaceGivesTheSameValues) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  torch::manual_seed(18);
  // 16 and 32 channels: the packed layouts fit in the weights' own bytes. 3 output channels: they do not
  // (blocked layouts pad the output channels to 16). 3 input channels fit on some CPUs and not on others
  // (on AMX the kernel's layout leaves them unpadded).
  const auto make = [] {
    torch::nn::Sequential model(Conv2d(16, 32, 3, 1, 1, true, torch::TensorOptions()),
                                Conv2d(32, 32, 3, 1, 1, false, torch::TensorOptions()),
                                Conv2d(32, 3, 1, 1, 0, true, torch::TensorOptions()),
                                Conv2d(3, 16, 3, 1, 1, true, torch::TensorOptions()));
    return model;
  };
  torch::nn::Sequential separate = make(), in_place = make();
  randomize_parameters(*separate, 0.2);
  set_precision(*separate, Precision::kBf16);
  set_precision(*in_place, Precision::kBf16);
  const auto weight = [](torch::nn::Sequential& m, size_t i) { return m[i]->as<Conv2dImpl>()->weight; };
  for (size_t i = 0; i < separate->size(); ++i) {
    weight(in_place, i).copy_(weight(separate, i));
    if (const torch::Tensor bias = separate[i]->as<Conv2dImpl>()->bias; bias.defined())
      in_place[i]->as<Conv2dImpl>()->bias.copy_(bias);
  }
  pack_weights_in_place(*in_place);
  const void* storage = weight(in_place, 0).data_ptr();

  const torch::Tensor x = torch::randn({2, 16, 8, 8}).to(torch::kBFloat16);
  const torch::Tensor expected = separate->forward(x);
  // The same kernels on the same packed values: the same result, and again on the next call.
  EXPECT_TRUE(torch::equal(in_place->forward(x), expected));
  EXPECT_TRUE(torch::equal(in_place->forward(x), expected));
  // The first two layers' weights now hold the packed layout in their own storage; the third kept its own.
  EXPECT_EQ(weight(in_place, 0).data_ptr(), storage);
  EXPECT_FALSE(torch::equal(weight(in_place, 0), weight(separate, 0)));
  EXPECT_FALSE(torch::equal(weight(in_place, 1), weight(separate, 1)));
  EXPECT_TRUE(torch::equal(weight(in_place, 2), weight(separate, 2)));
  // Another input size gets its own plan from the packed values.
  const torch::Tensor larger = torch::randn({1, 16, 11, 5}).to(torch::kBFloat16);
  EXPECT_TRUE(torch::equal(in_place->forward(larger), separate->forward(larger)));
  // New values copied in (as a weight loader does) are packed again.
  weight(in_place, 0).copy_(weight(separate, 0).neg());
  weight(separate, 0).neg_();
  EXPECT_TRUE(torch::equal(in_place->forward(x), separate->forward(x)));
  EXPECT_FALSE(torch::equal(separate->forward(x), expected));
}

TEST(Bf16Kernels, ConvolutionRejectsAChannelMismatch) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  Conv2d conv(8, 4, 3, 1, 1, true, torch::TensorOptions());
  set_precision(*conv, Precision::kBf16);
  EXPECT_THROW(conv->forward(torch::zeros({1, 6, 4, 4}, torch::kBFloat16)), c10::Error);
}

// GroupNorm of the same bf16 values in fp32 by ATen, then SiLU in fp32 if asked.
// In double and NCHW: ATen 1.13's fp32 GroupNorm of channels-last input drifts at large offsets.
torch::Tensor group_norm_reference(const torch::Tensor& x, const GroupNorm& norm, bool silu) {
  torch::Tensor y = torch::group_norm(x.to(torch::kDouble).contiguous(), norm->groups, norm->weight.to(torch::kDouble),
                                      norm->bias.to(torch::kDouble), norm->eps);
  return silu ? torch::silu(y) : y;
}

struct NormCase {
  int64_t batch, channels, groups, height, width;
};

testing::Message describe(const NormCase& c) {
  return testing::Message() << c.batch << "x" << c.channels << "x" << c.height << "x" << c.width;
}

// Activations of `type` with a large common offset and a wide range (mean 200, standard deviation 3),
// channels-last: variance from E[x^2] - mean^2 would lose it, and so does ATen 1.13's fp32 GroupNorm of
// channels-last input (off by up to 0.14, docs/networks.md).
torch::Tensor offset_activations(const NormCase& c, torch::ScalarType type) {
  return (torch::randn({c.batch, c.channels, c.height, c.width}) * 3.0 + 200.0)
      .to(type)
      .contiguous(at::MemoryFormat::ChannelsLast);
}

TEST(Bf16Kernels, GroupNormOfChannelsLastInputMatchesFp32) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(13);
  // 70x70 pixels: 19 full blocks of the statistics and a partial one; 1x1: a single pixel.
  for (const NormCase& c : {NormCase{2, 64, 32, 9, 7}, NormCase{1, 32, 8, 70, 70}, NormCase{3, 12, 3, 1, 1}}) {
    SCOPED_TRACE(describe(c));
    GroupNorm norm(c.groups, c.channels, 1e-6, torch::TensorOptions());
    randomize_parameters(*norm, 1.0);
    const torch::Tensor x = offset_activations(c, torch::kBFloat16);
    ASSERT_TRUE(group_norm_channels_last_applies(x, norm->weight));
    for (bool silu : {false, true}) {
      SCOPED_TRACE(silu ? "with SiLU" : "plain");
      const torch::Tensor y = silu ? norm->forward_silu(x) : norm->forward(x);
      EXPECT_EQ(y.scalar_type(), torch::kBFloat16);
      EXPECT_TRUE(y.is_contiguous(at::MemoryFormat::ChannelsLast));
      EXPECT_TRUE(within_one_bf16_step(y, group_norm_reference(x, norm, silu)));
    }
  }
}

TEST(Bf16Kernels, GroupNormSiluCoversTheWholeRange) {
  torch::NoGradGuard no_grad;
  // Normalised values from -100 to 100 (weight 1, bias 0 would squeeze them): SiLU's exp must neither
  // overflow nor lose the small tail.
  GroupNorm norm(1, 16, 1e-6, torch::TensorOptions());
  norm->weight.fill_(40.0);
  norm->bias.zero_();
  const torch::Tensor x = torch::linspace(-2.5, 2.5, 16 * 64)
                              .reshape({1, 16, 8, 8})
                              .to(torch::kBFloat16)
                              .contiguous(at::MemoryFormat::ChannelsLast);
  const torch::Tensor y = norm->forward_silu(x);
  EXPECT_TRUE(torch::isfinite(y).all().item<bool>());
  EXPECT_TRUE(within_one_bf16_step(y, group_norm_reference(x, norm, true)));
}

TEST(Bf16Kernels, GroupNormDoesNotDependOnTheThreadCount) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(14);
  GroupNorm norm(8, 32, 1e-6, torch::TensorOptions());
  randomize_parameters(*norm, 1.0);
  const torch::Tensor x = torch::randn({2, 32, 40, 40}).to(torch::kBFloat16).contiguous(at::MemoryFormat::ChannelsLast);
  const int threads = at::get_num_threads();
  at::set_num_threads(1);
  const torch::Tensor one = norm->forward_silu(x);
  at::set_num_threads(std::max(threads, 2));
  const torch::Tensor many = norm->forward_silu(x);
  at::set_num_threads(threads);
  EXPECT_TRUE(torch::equal(one, many));
}

// The same values at other addresses give the same bits (the seeded runs of the pipeline depend on it):
// the input at each element offset of a 64-byte line, and the kernel's own per-channel scratch, small
// heap blocks, at other places relative to each other (blocks of its size taken and given back in turn
// before each call). 8, 20 and 40 channels leave a partial vector per pixel (the tiny models have 8).
TEST(Fp32Kernels, GroupNormDoesNotDependOnWhereItsDataLies) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(24);
  for (const torch::ScalarType type : {torch::kFloat, torch::kBFloat16}) {
    for (const int64_t channels : {8, 20, 40, 64}) {
      SCOPED_TRACE(testing::Message() << channels << " channels, " << c10::toString(type));
      GroupNorm norm(4, channels, 1e-6, torch::TensorOptions());
      randomize_parameters(*norm, 1.0);
      const torch::Tensor x = torch::randn({1, channels, 16, 16}).to(type).contiguous(at::MemoryFormat::ChannelsLast);
      const torch::Tensor expected = norm->forward_silu(x);
      std::vector<std::unique_ptr<float[]>> blocks;
      int differing = 0;
      for (int64_t trial = 0; trial < 256; ++trial) {
        for (int64_t k = 0; k < trial % 5; ++k) blocks.push_back(std::make_unique<float[]>(size_t(channels)));
        for (size_t k = 0; k < blocks.size(); k += 1 + size_t(trial % 3)) blocks[k].reset();
        std::erase(blocks, nullptr);
        const int64_t offset = trial % 16;
        const torch::Tensor storage = torch::empty({x.numel() + offset}, type);
        const torch::Tensor moved = storage.narrow(0, offset, x.numel()).as_strided(x.sizes(), x.strides()).copy_(x);
        ASSERT_TRUE(group_norm_channels_last_applies(moved, norm->weight));
        differing += !torch::equal(norm->forward_silu(moved), expected);
      }
      EXPECT_EQ(differing, 0) << "of 256 calls";
    }
  }
}

// ATen's fp32 GroupNorm of the NCHW input, rounded to bf16, then SiLU: bit for bit. (Not the float64
// reference: fp32 statistics round to a neighbouring bf16 value now and then, and CI failed on one.)
TEST(Bf16Kernels, GroupNormOfOtherLayoutsStaysWithAten) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(25);
  GroupNorm norm(4, 16, 1e-5, torch::TensorOptions());
  randomize_parameters(*norm, 1.0);  // not left uninitialised: whatever memory held (NaN fails the comparison)
  const torch::Tensor x = torch::randn({2, 16, 5, 5}).to(torch::kBFloat16);  // NCHW
  EXPECT_FALSE(group_norm_channels_last_applies(x, norm->weight));
  EXPECT_FALSE(group_norm_channels_last_applies(x.to(torch::kFloat), norm->weight));
  EXPECT_FALSE(
      group_norm_channels_last_applies(x.to(torch::kDouble).contiguous(at::MemoryFormat::ChannelsLast), norm->weight));
  const torch::Tensor y = norm->forward_silu(x);
  const torch::Tensor aten = torch::group_norm(x.to(torch::kFloat), norm->groups, norm->weight, norm->bias, norm->eps);
  EXPECT_TRUE(torch::equal(y, torch::silu(aten.to(torch::kBFloat16))));
  EXPECT_TRUE(within_one_bf16_step(norm->forward(x), group_norm_reference(x, norm, false)));
}

TEST(Fp32Kernels, ConvolutionMatchesFloat64) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(21);
  for (const ConvCase& c : kConvCases) {
    SCOPED_TRACE(describe(c));
    Conv2d conv(c.in, c.out, c.kernel, c.stride, c.padding, c.bias, torch::TensorOptions());
    randomize_parameters(*conv, 0.2);
    const torch::Tensor x = torch::randn({c.batch, c.in, c.height, c.width});
    ASSERT_TRUE(OnednnConv2d::applies(x, conv->weight));
    const torch::Tensor y = conv->forward(x);
    EXPECT_EQ(y.scalar_type(), torch::kFloat);
    EXPECT_TRUE(y.is_contiguous(at::MemoryFormat::ChannelsLast));
    const torch::Tensor bias = c.bias ? conv->bias.to(torch::kDouble) : torch::Tensor();
    const torch::Tensor expected = torch::conv2d(x.to(torch::kDouble), conv->weight.to(torch::kDouble), bias,
                                                 {c.stride, c.stride}, {c.padding, c.padding});
    ASSERT_EQ(y.sizes(), expected.sizes());
    EXPECT_LT(relative_error(y.to(torch::kDouble), expected), 1e-6);
    EXPECT_TRUE(torch::equal(conv->forward(x.contiguous(at::MemoryFormat::ChannelsLast)), y));
  }
}

TEST(Fp32Kernels, ConvolutionPackedInPlaceGivesTheSameValues) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(22);
  const auto make = [] {
    torch::nn::Sequential model(Conv2d(16, 32, 3, 1, 1, true, torch::TensorOptions()),
                                Conv2d(32, 3, 1, 1, 0, true, torch::TensorOptions()),
                                Conv2d(3, 16, 3, 1, 1, true, torch::TensorOptions()));
    return model;
  };
  torch::nn::Sequential separate = make(), in_place = make();
  randomize_parameters(*separate, 0.2);
  for (size_t i = 0; i < separate->size(); ++i)
    for (const auto& item : separate[i]->named_parameters())
      in_place[i]->named_parameters()[item.key()].copy_(item.value());
  pack_weights_in_place(*in_place);
  const torch::Tensor x = torch::randn({2, 16, 8, 8});
  const torch::Tensor expected = separate->forward(x);
  EXPECT_TRUE(torch::equal(in_place->forward(x), expected));
  EXPECT_TRUE(torch::equal(in_place->forward(x), expected));
  // The first layer's weights hold the packed layout now.
  EXPECT_FALSE(torch::equal(in_place[0]->as<Conv2dImpl>()->weight, separate[0]->as<Conv2dImpl>()->weight));
  const torch::Tensor larger = torch::randn({1, 16, 11, 5});
  EXPECT_TRUE(torch::equal(in_place->forward(larger), separate->forward(larger)));
}

TEST(Fp32Kernels, GroupNormOfChannelsLastInputMatchesFloat64) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(23);
  // 20 channels: a partial vector of 4 at the end of each pixel.
  for (const NormCase& c : {NormCase{2, 64, 32, 9, 7}, NormCase{1, 32, 8, 70, 70}, NormCase{3, 20, 5, 3, 1}}) {
    SCOPED_TRACE(describe(c));
    GroupNorm norm(c.groups, c.channels, 1e-6, torch::TensorOptions());
    randomize_parameters(*norm, 1.0);
    const torch::Tensor x = offset_activations(c, torch::kFloat);
    ASSERT_TRUE(group_norm_channels_last_applies(x, norm->weight));
    for (bool silu : {false, true}) {
      SCOPED_TRACE(silu ? "with SiLU" : "plain");
      const torch::Tensor y = silu ? norm->forward_silu(x) : norm->forward(x);
      EXPECT_EQ(y.scalar_type(), torch::kFloat);
      EXPECT_TRUE(y.is_contiguous(at::MemoryFormat::ChannelsLast));
      // x * scale + shift cancels at this offset: a few fp32 steps of 200 * scale (ATen's NCHW version
      // is off by 1.5e-5 here too).
      const torch::Tensor expected = group_norm_reference(x, norm, silu);
      EXPECT_LT((y.to(torch::kDouble) - expected).abs().max().item<double>(), 5e-5);
    }
  }
}

TEST(Bf16Kernels, ScaledSoftmaxMatchesFloat64) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(15);
  const double scale = 1.0 / std::sqrt(40.0);
  // 4,096 and 1,024 keys (whole vectors), 77 (a tail of 13), 5 (a tail only) and 1.
  for (const int64_t keys : {4096, 1024, 77, 5, 1}) {
    SCOPED_TRACE(testing::Message() << keys << " keys");
    // Scores up to about +-400: after the scale, exp spans far more than fp32 (the small ones must
    // come out as 0, not as garbage or NaN).
    torch::Tensor scores = (torch::randn({3, 7, keys}) * 100.0).to(torch::kBFloat16);
    const torch::Tensor expected = (scores.to(torch::kDouble) * scale).softmax(-1);
    ASSERT_TRUE(scaled_softmax_applies(scores));
    scaled_softmax_(scores, scale);
    EXPECT_EQ(scores.scalar_type(), torch::kBFloat16);
    EXPECT_TRUE(within_one_bf16_step(scores, expected));
    // Rows sum to one within bf16's rounding.
    EXPECT_LT((scores.to(torch::kDouble).sum(-1) - 1.0).abs().max().item<double>(), 1e-2);
  }
}

TEST(Bf16Kernels, ScaledSoftmaxOfMaskedScores) {
  torch::NoGradGuard no_grad;
  const float inf = std::numeric_limits<float>::infinity();
  torch::Tensor scores = torch::tensor({0.0f, -inf, 1.0f, -inf, 2.0f}).reshape({1, 5}).to(torch::kBFloat16);
  scaled_softmax_(scores, 1.0);
  const torch::Tensor expected = torch::tensor({0.0f, -inf, 1.0f, -inf, 2.0f}).to(torch::kDouble).softmax(-1);
  EXPECT_TRUE(within_one_bf16_step(scores.reshape({5}), expected));
  EXPECT_EQ(scores[0][1].item<float>(), 0.0f);
  // A row of -inf only has no softmax: NaN, as ATen's.
  torch::Tensor masked = torch::full({2, 20}, -inf).to(torch::kBFloat16);
  scaled_softmax_(masked, 1.0);
  EXPECT_TRUE(torch::isnan(masked).all().item<bool>());
  torch::Tensor fp32 = torch::zeros({2, 3});
  EXPECT_FALSE(scaled_softmax_applies(fp32));
  EXPECT_THROW(scaled_softmax_(fp32, 1.0), c10::Error);
}

// The whole attention in bf16 against fp32 on the same bf16 inputs, in one block and in blocks of
// queries (a small score budget).
TEST(Bf16Kernels, AttentionMatchesFp32OnTheSameValues) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(16);
  const int64_t heads = 4;
  const torch::Tensor q = torch::randn({2, 300, heads * 40}).to(torch::kBFloat16);
  const torch::Tensor k = torch::randn({2, 77, heads * 40}).to(torch::kBFloat16);
  const torch::Tensor v = torch::randn({2, 77, heads * 40}).to(torch::kBFloat16);
  const double scale = 1.0 / std::sqrt(40.0);
  const torch::Tensor expected =
      multi_head_attention(q.to(torch::kFloat), k.to(torch::kFloat), v.to(torch::kFloat), heads, scale);
  for (const int64_t budget : {kDefaultAttentionScoreBudget, int64_t{77 * 32}}) {
    SCOPED_TRACE(testing::Message() << "score budget " << budget);
    const torch::Tensor out = multi_head_attention(q, k, v, heads, scale, budget);
    EXPECT_EQ(out.scalar_type(), torch::kBFloat16);
    EXPECT_LT(relative_error(out.to(torch::kFloat), expected), 1e-2);
  }
}

// The fused bf16 attention against float64 on the same bf16 values: lengths that are not multiples of its
// tiles (32 queries, 64 keys, pairs of keys), one key, the models' head sizes, large scores, a strided key view.
TEST(Bf16Kernels, FusedAttentionMatchesFloat64) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  torch::manual_seed(18);
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
    const torch::Tensor q = (torch::randn({c.batch, c.queries, channels}) * c.magnitude).to(torch::kBFloat16);
    const torch::Tensor k =
        (torch::randn({c.batch, c.keys, 2 * channels}) * c.magnitude).to(torch::kBFloat16).narrow(2, 0, channels);
    const torch::Tensor v = torch::randn({c.batch, c.keys, channels}).to(torch::kBFloat16);
    ASSERT_TRUE(fused_attention_applies(q, k, v, c.heads));
    const double scale = 1.0 / std::sqrt(double(c.dim));
    const torch::Tensor out = fused_attention(q, k, v, c.heads, scale);
    EXPECT_EQ(out.scalar_type(), torch::kBFloat16);
    const auto split = [&](const torch::Tensor& x) {
      return x.to(torch::kDouble).reshape({c.batch, x.size(1), c.heads, c.dim}).permute({0, 2, 1, 3});
    };
    const torch::Tensor expected = torch::matmul((torch::matmul(split(q), split(k).transpose(-1, -2)) * scale).softmax(-1),
                                                 split(v))
                                       .permute({0, 2, 1, 3})
                                       .reshape({c.batch, c.queries, channels});
    // Scores exact to fp32, probabilities and the output rounded to bf16 once each (2^-9 relative).
    EXPECT_LT(relative_error(out, expected), 5e-3);
    EXPECT_LT((out.to(torch::kDouble) - expected).abs().max().item<double>(), 2e-2);
    EXPECT_TRUE(torch::equal(multi_head_attention(q, k, v, c.heads, scale), out));
  }
}

TEST(Bf16Kernels, GegluMatchesFloat64) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(17);
  // 40 gates a row: two vectors and a tail of 8. Gates from -12 to 12: GELU's small negative tail
  // (about -1e-32 at -12) must keep its relative accuracy.
  const torch::Tensor hidden = torch::randn({3, 5, 40});
  const torch::Tensor gate = torch::linspace(-12.0, 12.0, 3 * 5 * 40).reshape({3, 5, 40});
  const torch::Tensor projected = torch::cat({hidden, gate}, -1).to(torch::kBFloat16);
  ASSERT_TRUE(geglu_applies(projected));
  const torch::Tensor out = geglu(projected);
  EXPECT_EQ(out.sizes(), hidden.sizes());
  const torch::Tensor h = projected.narrow(-1, 0, 40).to(torch::kDouble);
  const torch::Tensor g = projected.narrow(-1, 40, 40).to(torch::kDouble);
  // gelu(g) = g/2 * erfc(-g/sqrt 2): through 1 + erf, as ATen computes it, float64 loses the tail below -8.
  EXPECT_TRUE(within_one_bf16_step(out, h * 0.5 * g * torch::erfc(-g / std::sqrt(2.0))));
  EXPECT_FALSE(geglu_applies(projected.narrow(-1, 0, 79)));                // odd and strided
  EXPECT_THROW(geglu(torch::zeros({2, 4}, torch::kDouble)), c10::Error);  // float64
}

TEST(Fp32Kernels, GegluMatchesFloat64) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(24);
  const torch::Tensor hidden = torch::randn({3, 5, 40});
  const torch::Tensor gate = torch::linspace(-12.0, 12.0, 3 * 5 * 40).reshape({3, 5, 40});
  const torch::Tensor projected = torch::cat({hidden, gate}, -1);
  ASSERT_TRUE(geglu_applies(projected));
  const torch::Tensor out = geglu(projected);
  EXPECT_EQ(out.scalar_type(), torch::kFloat);
  const torch::Tensor h = hidden.to(torch::kDouble), g = gate.to(torch::kDouble);
  const torch::Tensor expected = h * 0.5 * g * torch::erfc(-g / std::sqrt(2.0));
  // Relative accuracy in the whole range, the small negative tail included (ATen's fp32 GELU, through
  // 1 + erf, keeps only absolute accuracy there): erfc's fit is good to 1.2e-7, but its exponent -z^2
  // is rounded in fp32 (at z = 12 / sqrt 2, z^2 = 72 has steps of 7.6e-6), which the tail inherits.
  const torch::Tensor relative = (out.to(torch::kDouble) - expected).abs() / (expected.abs() + 1e-300);
  EXPECT_LT(relative.max().item<double>(), 2e-5);
  EXPECT_LT(relative.masked_select(g > -3.0).max().item<double>(), 1e-6);
}

TEST(Bf16Kernels, LayerNormMatchesFloat64) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(31);
  // Rows of 320 (the UNet's first level: ten pairs of vectors), 40 (two vectors and a tail of 8) and 7
  // (a tail alone); values about a mean of 200, where a one-pass variance in fp32 would lose its digits.
  for (const int64_t n : {320, 40, 7}) {
    SCOPED_TRACE(testing::Message() << n << " values a row");
    const torch::Tensor x = (torch::randn({3, 37, n}) * 0.5 + 200).to(torch::kBFloat16);
    const torch::Tensor weight = torch::randn({n}), bias = torch::randn({n});
    ASSERT_TRUE(layer_norm_bf16_applies(x, weight, bias));
    const torch::Tensor out = layer_norm_bf16(x, weight, bias, 1e-5);
    EXPECT_EQ(out.scalar_type(), torch::kBFloat16);
    EXPECT_EQ(out.sizes(), x.sizes());
    const torch::Tensor expected = torch::layer_norm(x.to(torch::kDouble), {n}, weight.to(torch::kDouble),
                                                     bias.to(torch::kDouble), 1e-5);
    // One bf16 step of the result, plus fp32's rounding of the two terms (x - mean)·rstd·w and b, each
    // of a few units, where they cancel to a result near 0.
    const torch::Tensor error = (out.to(torch::kDouble) - expected).abs() - expected.abs() / 128;
    EXPECT_LT(error.max().item<double>(), 1e-4);
    // The layer takes this kernel for bf16 activations, and the same values come out at any thread count.
    LayerNorm layer(n, 1e-5, torch::TensorOptions().dtype(torch::kFloat));
    layer->weight.copy_(weight);
    layer->bias.copy_(bias);
    EXPECT_TRUE(torch::equal(layer->forward(x), out));
    const int threads = at::get_num_threads();
    at::set_num_threads(1);
    EXPECT_TRUE(torch::equal(layer_norm_bf16(x, weight, bias, 1e-5), out));
    at::set_num_threads(threads);
  }
  const torch::Tensor x = torch::randn({4, 16}).to(torch::kBFloat16), w = torch::ones({16}), b = torch::zeros({16});
  EXPECT_FALSE(layer_norm_bf16_applies(x.t(), w, b));                            // strided
  EXPECT_FALSE(layer_norm_bf16_applies(x, w.to(torch::kBFloat16), b));           // bf16 weights: ATen
  EXPECT_FALSE(layer_norm_bf16_applies(x.narrow(1, 0, 8).contiguous(), w, b));   // a size mismatch
  EXPECT_THROW(layer_norm_bf16(x.to(torch::kFloat), w, b, 1e-5), c10::Error);   // fp32 stays with ATen
}

}  // namespace
}  // namespace u3d::nn
