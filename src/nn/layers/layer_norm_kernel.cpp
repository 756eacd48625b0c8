#include "nn/layers/layer_norm_kernel.h"

#include "nn/layers/vector_math.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace u3d::nn {

namespace {

using namespace vector_math;

// Lane i < count of 16.
U3D_INLINE i32x16 lanes_below(int64_t count) {
  i32x16 mask{};
  for (int i = 0; i < kWidth; ++i) mask[i] = i < count ? -1 : 0;
  return mask;
}

// One row of n values: its mean, the sum of squared deviations from it, then the normalised output.
U3D_VECTOR_CLONES void normalise_row(const uint16_t* x, int64_t n, const float* weight, const float* bias, float eps,
                                     uint16_t* out) {
  const int64_t full = n / kWidth * kWidth;
  f32x16 sum{}, sum2{};
  int64_t j = 0;
  for (; j + 2 * kWidth <= full; j += 2 * kWidth) {
    sum += load_bf16(x + j);
    sum2 += load_bf16(x + j + kWidth);
  }
  if (j < full) sum += load_bf16(x + j);
  if (full < n) sum2 += load_bf16_tail(x + full, n - full, 0);
  const float mean = horizontal_sum(sum + sum2) / static_cast<float>(n);
  f32x16 squares{}, squares2{};
  for (j = 0; j + 2 * kWidth <= full; j += 2 * kWidth) {
    const f32x16 d = load_bf16(x + j) - mean, d2 = load_bf16(x + j + kWidth) - mean;
    squares += d * d;
    squares2 += d2 * d2;
  }
  if (j < full) {
    const f32x16 d = load_bf16(x + j) - mean;
    squares += d * d;
  }
  if (full < n) {
    const f32x16 d = load_bf16_tail(x + full, n - full, 0) - mean;
    squares2 += lanes_below(n - full) ? d * d : f32x16{};
  }
  const float variance = horizontal_sum(squares + squares2) / static_cast<float>(n);
  const float rstd = static_cast<float>(1.0 / std::sqrt(static_cast<double>(variance) + eps));
  for (j = 0; j < full; j += kWidth)
    store_bf16(out + j, (load_bf16(x + j) - mean) * rstd * load(weight + j) + load(bias + j));
  for (; j < n; ++j) {
    uint16_t rounded[kWidth];
    store_bf16(rounded, splat((bf16_to_float(x[j]) - mean) * rstd * weight[j] + bias[j]));
    out[j] = rounded[0];
  }
}

}  // namespace

bool layer_norm_bf16_applies(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias) {
  return x.device().is_cpu() && x.scalar_type() == torch::kBFloat16 && x.dim() >= 1 && x.is_contiguous() &&
         weight.dim() == 1 && bias.dim() == 1 && weight.scalar_type() == torch::kFloat &&
         bias.scalar_type() == torch::kFloat && weight.device().is_cpu() && bias.device().is_cpu() &&
         weight.is_contiguous() && bias.is_contiguous() && x.size(-1) == weight.size(0) &&
         bias.size(0) == weight.size(0);
}

torch::Tensor layer_norm_bf16(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias,
                              double eps) {
  TORCH_CHECK(layer_norm_bf16_applies(x, weight, bias),
              "layer_norm_bf16: not a contiguous bf16 CPU tensor with fp32 weight and bias of its last dimension");
  torch::Tensor out = torch::empty_like(x);
  const int64_t n = x.size(-1);
  if (x.numel() == 0) return out;
  const int64_t rows = x.numel() / n;
  const auto* in = reinterpret_cast<const uint16_t*>(x.data_ptr());
  auto* result = reinterpret_cast<uint16_t*>(out.data_ptr());
  const float* gamma = weight.data_ptr<float>();
  const float* beta = bias.data_ptr<float>();
  const auto epsilon = static_cast<float>(eps);
  at::parallel_for(0, rows, std::max<int64_t>(1, (int64_t{1} << 14) / n), [&](int64_t begin, int64_t end) {
    for (int64_t r = begin; r < end; ++r) normalise_row(in + r * n, n, gamma, beta, epsilon, result + r * n);
  });
  return out;
}

}  // namespace u3d::nn
