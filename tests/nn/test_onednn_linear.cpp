#include "nn/layers/onednn_linear.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "nn/layers/layers.h"
#include "nn/runtime.h"

namespace u3d::nn {
namespace {

// The largest |a - b| over |b|'s largest value.
double relative_max_error(const torch::Tensor& a, const torch::Tensor& b) {
  return ((a.to(torch::kDouble) - b).abs().max() / b.abs().max()).item<double>();
}

TEST(OnednnLinear, MatchesFloat64) {
  if (!cpu_runs_avx512_kernels()) GTEST_SKIP() << "fp32 linear layers take ATen's path on this CPU";
  torch::manual_seed(3);
  // A 3-D input of odd sizes, with and without bias, and a strided (transposed) input.
  const torch::Tensor x = torch::randn({3, 37, 70});
  const torch::Tensor weight = torch::randn({45, 70}) * 0.1, bias = torch::randn({45});
  const torch::Tensor reference = torch::linear(x.to(torch::kDouble), weight.to(torch::kDouble), bias.to(torch::kDouble));
  const torch::Tensor out = onednn_linear(x, weight, bias);
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{3, 37, 45}));
  EXPECT_LT(relative_max_error(out, reference), 1e-6);
  const torch::Tensor no_bias = onednn_linear(x, weight, {});
  EXPECT_LT(relative_max_error(no_bias, torch::linear(x.to(torch::kDouble), weight.to(torch::kDouble))), 1e-6);
  const torch::Tensor strided = torch::randn({70, 11}).t();
  EXPECT_LT(relative_max_error(onednn_linear(strided, weight, bias),
                               torch::linear(strided.to(torch::kDouble), weight.to(torch::kDouble),
                                             bias.to(torch::kDouble))),
            1e-6);
  // A single row: the output is a new tensor, the bias is left as it was.
  const torch::Tensor bias_before = bias.clone();
  const torch::Tensor row = x.narrow(0, 0, 1).narrow(1, 0, 1);
  EXPECT_LT(relative_max_error(onednn_linear(row, weight, bias),
                               torch::linear(row.to(torch::kDouble), weight.to(torch::kDouble), bias.to(torch::kDouble))),
            1e-6);
  EXPECT_TRUE(torch::equal(bias, bias_before));
  // The Linear layer takes this path for fp32.
  Linear layer(70, 45, true, torch::TensorOptions());
  layer->weight.data().copy_(weight);
  layer->bias.data().copy_(bias);
  EXPECT_TRUE(torch::equal(layer->forward(x), out));
}

}  // namespace
}  // namespace u3d::nn
