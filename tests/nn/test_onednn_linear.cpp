#include "nn/layers/onednn_linear.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "nn/layers/layers.h"
#include "nn/layers/transformer_2d.h"
#include "nn/precision.h"
#include "nn/runtime.h"
#include "required_skip.h"

namespace u3d::nn {
namespace {

// The largest |a - b| over |b|'s largest value.
double relative_max_error(const torch::Tensor& a, const torch::Tensor& b) {
  return ((a.to(torch::kDouble) - b).abs().max() / b.abs().max()).item<double>();
}

torch::Tensor reference(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias) {
  return torch::linear(x.to(torch::kDouble), weight.to(torch::kDouble),
                       bias.defined() ? bias.to(torch::kDouble) : torch::Tensor());
}

// Odd sizes, with and without bias, a strided (transposed) input and a single row, against float64 of the
// same (rounded) inputs; bf16 results are rounded once, so within 2^-8 of the largest value.
void check_against_float64(torch::ScalarType type, double tolerance) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(3);
  const torch::Tensor x = torch::randn({3, 37, 70}).to(type);
  const torch::Tensor weight = (torch::randn({45, 70}) * 0.1).to(type), bias = torch::randn({45}).to(type);
  ASSERT_TRUE(OnednnLinear::applies(x, weight));
  OnednnLinear linear;
  const torch::Tensor out = linear.forward(x, weight, bias);
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{3, 37, 45}));
  EXPECT_EQ(out.scalar_type(), type);
  EXPECT_LT(relative_max_error(out, reference(x, weight, bias)), tolerance);
  OnednnLinear no_bias;
  EXPECT_LT(relative_max_error(no_bias.forward(x, weight, {}), reference(x, weight, {})), tolerance);
  const torch::Tensor strided = torch::randn({70, 11}).to(type).t();
  EXPECT_LT(relative_max_error(linear.forward(strided, weight, bias), reference(strided, weight, bias)), tolerance);
  // A single row: the output is a new tensor, the bias is left as it was.
  const torch::Tensor bias_before = bias.clone();
  const torch::Tensor row = x.narrow(0, 0, 1).narrow(1, 0, 1);
  EXPECT_LT(relative_max_error(linear.forward(row, weight, bias), reference(row, weight, bias)), tolerance);
  EXPECT_TRUE(torch::equal(bias, bias_before));
  // The first row count's plan still answers.
  EXPECT_TRUE(torch::equal(linear.forward(x, weight, bias), out));
  // An fp32 bias is added before the rounding.
  OnednnLinear fp32_bias;
  const torch::Tensor bias32 = torch::randn({45});
  EXPECT_LT(relative_max_error(fp32_bias.forward(x, weight, bias32), reference(x, weight, bias32)), tolerance);
  // The Linear layer takes this path.
  Linear layer(70, 45, true, torch::TensorOptions().dtype(type));
  layer->weight.copy_(weight);
  layer->bias.copy_(bias);
  EXPECT_TRUE(torch::equal(layer->forward(x), out));
}

TEST(OnednnLinear, Fp32MatchesFloat64) {
  if (!cpu_runs_avx512_kernels()) GTEST_SKIP() << "fp32 linear layers take ATen's path on this CPU";
  check_against_float64(torch::kFloat, 1e-6);
}

TEST(OnednnLinear, Bf16MatchesFloat64) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  check_against_float64(torch::kBFloat16, 1.0 / 256);
}

// Packed into their own storage, the weights give what the plain weights give (the same kernel, the same
// products: equal here), for every row count; new values copied in are packed again; a path that would
// read the packed bytes as plain weights refuses.
void check_packed_in_place(torch::ScalarType type) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(11);
  const torch::TensorOptions options = torch::TensorOptions().dtype(type);
  // 64 -> 320 and 320 -> 64 (no bias): packed layouts that fit in the weights' bytes. 64 -> 48: they do
  // not (the layouts pad the outputs to 64 here), so those weights stay plain.
  const auto make = [&] {
    return torch::nn::Sequential(Linear(64, 320, true, options), Linear(320, 64, false, options),
                                 Linear(64, 48, true, options));
  };
  torch::nn::Sequential plain = make(), in_place = make();
  randomize_parameters(*plain, 0.1);
  for (size_t i = 0; i < plain->size(); ++i)
    for (const auto& item : plain[i]->named_parameters()) in_place[i]->named_parameters()[item.key()].copy_(item.value());
  pack_weights_in_place(*in_place);
  const auto weight = [](torch::nn::Sequential& m, size_t i) { return m[i]->as<LinearImpl>()->weight; };
  const void* storage = weight(in_place, 0).data_ptr();

  const torch::Tensor x = torch::randn({2, 100, 64}).to(type);
  const torch::Tensor expected = plain->forward(x);
  const torch::Tensor hidden = reference(x, weight(plain, 0), plain[0]->as<LinearImpl>()->bias);
  EXPECT_LT(relative_max_error(expected, reference(reference(hidden, weight(plain, 1), {}), weight(plain, 2),
                                                   plain[2]->as<LinearImpl>()->bias)),
            type == torch::kFloat ? 1e-6 : 3.0 / 256);
  EXPECT_TRUE(torch::equal(in_place->forward(x), expected));
  EXPECT_TRUE(torch::equal(in_place->forward(x), expected));
  EXPECT_EQ(weight(in_place, 0).data_ptr(), storage);
  for (size_t i = 0; i < 2; ++i)
    EXPECT_FALSE(torch::equal(weight(in_place, i), weight(plain, i))) << "layer " << i << " was not packed";
  EXPECT_TRUE(torch::equal(weight(in_place, 2), weight(plain, 2)));
  // Other row counts get their own plans on the packed values.
  for (int64_t rows : {1, 7, 513}) {
    const torch::Tensor other = torch::randn({rows, 64}).to(type);
    EXPECT_TRUE(torch::equal(in_place->forward(other), plain->forward(other))) << rows << " rows";
  }
  // New values copied in, as a weight loader does: packed again from them.
  const torch::Tensor fresh = (torch::randn({320, 64}) * 0.1).to(type);
  weight(plain, 0).copy_(fresh);
  weight(in_place, 0).copy_(fresh);
  EXPECT_TRUE(torch::equal(in_place->forward(x), plain->forward(x)));
  EXPECT_FALSE(torch::equal(weight(in_place, 0), fresh));
  // An input of another dtype would take ATen's path over the packed bytes.
  const torch::ScalarType other_type = type == torch::kFloat ? torch::kDouble : torch::kFloat;
  EXPECT_THROW(in_place->forward(x.to(other_type)), c10::Error);
}

TEST(OnednnLinear, Fp32PackedInPlaceGivesTheSameValues) {
  if (!cpu_runs_avx512_kernels()) GTEST_SKIP() << "fp32 linear layers take ATen's path on this CPU";
  check_packed_in_place(torch::kFloat);
}

TEST(OnednnLinear, Bf16PackedInPlaceGivesTheSameValues) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  check_packed_in_place(torch::kBFloat16);
}

// GEGLU's projection in two products with the gating applied as they are written (LinearImpl::
// gated_forward): hidden * gelu(gate) against float64 of the same (rounded) weights, packed or not;
// the split layer's plain forward still gives the whole projection [hidden | gate].
void check_gated(torch::ScalarType type, double tolerance) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(19);
  const torch::TensorOptions options = torch::TensorOptions().dtype(type);
  GEGLU plain(64, 128, options), packed(64, 128, options);  // 64 -> halves of 128: packed layouts that fit
  randomize_parameters(*plain, 0.3);
  for (const auto& item : plain->named_parameters()) packed->named_parameters()[item.key()].copy_(item.value());
  const torch::Tensor weight = plain->proj->weight.to(torch::kDouble), bias = plain->proj->bias.to(torch::kDouble);
  pack_weights_in_place(*packed);
  EXPECT_FALSE(torch::equal(packed->proj->weight, plain->proj->weight));

  const torch::Tensor x = (torch::randn({2, 37, 64}) * 2).to(type);
  const torch::Tensor projection = torch::linear(x.to(torch::kDouble), weight, bias);
  const torch::Tensor h = projection.narrow(-1, 0, 128), g = projection.narrow(-1, 128, 128);
  ASSERT_GT(g.abs().max().item<double>(), 3.0) << "the gates should reach GELU's curved range and beyond";
  const torch::Tensor expected = h * 0.5 * g * torch::erfc(-g / std::sqrt(2.0));
  ASSERT_TRUE(plain->proj->gated_forward_applies(x));
  const torch::Tensor out = plain->forward(x);
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{2, 37, 128}));
  EXPECT_EQ(out.scalar_type(), type);
  EXPECT_LT(relative_max_error(out, expected), tolerance);
  EXPECT_TRUE(torch::equal(packed->forward(x), out));
  // The GELU matches the standalone kernel's, the projection of the split layer is the whole one.
  EXPECT_LT(relative_max_error(plain->proj->forward(x), projection), type == torch::kFloat ? 1e-6 : 1.0 / 256);
  EXPECT_TRUE(torch::equal(packed->proj->forward(x), plain->proj->forward(x)));
  // A factor of another shape is refused.
  OnednnLinear linear;
  EXPECT_THROW(linear.forward(x, plain->proj->weight, {}, OnednnLinear::Epilogue::multiply, out), c10::Error);
}

TEST(OnednnLinear, Fp32GatedProductMatchesFloat64) {
  if (!cpu_runs_avx512_kernels()) GTEST_SKIP() << "fp32 linear layers take ATen's path on this CPU";
  check_gated(torch::kFloat, 1e-5);
}

TEST(OnednnLinear, Bf16GatedProductMatchesFloat64) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  // The GELU of the gate rounded to bf16, then the product: two roundings of 2^-9.
  check_gated(torch::kBFloat16, 2.0 / 256);
}

}  // namespace
}  // namespace u3d::nn
