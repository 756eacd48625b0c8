#include "nn/layers/softmax_kernel.h"

#include "nn/layers/vector_math.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

namespace u3d::nn {

namespace {

using namespace vector_math;

constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr uint16_t kBf16MinusInfinity = 0xff80;

U3D_INLINE float horizontal_max(f32x16 v) {
  float m = v[0];
  for (int64_t j = 1; j < kWidth; ++j) m = std::max(m, v[j]);
  return m;
}

U3D_VECTOR_CLONES float row_max(const uint16_t* x, int64_t n) {
  f32x16 m = splat(-kInfinity);
  int64_t i = 0;
  for (; i + kWidth <= n; i += kWidth) {
    const f32x16 v = load_bf16(x + i);
    m = v > m ? v : m;
  }
  if (i < n) {
    const f32x16 v = load_bf16_tail(x + i, n - i, kBf16MinusInfinity);
    m = v > m ? v : m;
  }
  return horizontal_max(m);
}

// e[i] = exp(scale * (x[i] - max)); returns the sum of e (16 partial sums, added at the end).
U3D_VECTOR_CLONES float exp_and_sum(const uint16_t* x, int64_t n, float max, float scale, float* e) {
  f32x16 sum{};
  int64_t i = 0;
  for (; i + kWidth <= n; i += kWidth) {
    const f32x16 v = exp_nonpositive((load_bf16(x + i) - max) * scale);
    store(e + i, v);
    sum += v;
  }
  if (i < n) {
    const f32x16 v = exp_nonpositive((load_bf16_tail(x + i, n - i, kBf16MinusInfinity) - max) * scale);
    float values[kWidth];
    store(values, v);
    std::copy(values, values + (n - i), e + i);
    sum += v;
  }
  return horizontal_sum(sum);
}

U3D_VECTOR_CLONES void scale_to_bf16(const float* e, int64_t n, float factor, uint16_t* out) {
  int64_t i = 0;
  for (; i + kWidth <= n; i += kWidth) store_bf16(out + i, load(e + i) * factor);
  if (i < n) {
    float values[kWidth] = {};
    std::copy(e + i, e + n, values);
    uint16_t rounded[kWidth];
    store_bf16(rounded, load(values) * factor);
    std::copy(rounded, rounded + (n - i), out + i);
  }
}

}  // namespace

bool scaled_softmax_applies(const torch::Tensor& scores) {
  return scores.device().is_cpu() && scores.scalar_type() == torch::kBFloat16 && scores.dim() >= 1 &&
         scores.is_contiguous();
}

void scaled_softmax_(torch::Tensor& scores, double scale) {
  TORCH_CHECK(scaled_softmax_applies(scores), "scaled_softmax_: not a contiguous bf16 CPU tensor");
  TORCH_CHECK(scale > 0.0, "scaled_softmax_: the scale must be positive");
  const int64_t cols = scores.size(-1);
  if (cols == 0) return;
  const int64_t rows = scores.numel() / cols;
  auto* data = reinterpret_cast<uint16_t*>(scores.data_ptr());
  const auto factor = static_cast<float>(scale);
  // Inside a parallel region (an attention task) this runs on the calling thread alone.
  at::parallel_for(0, rows, std::max<int64_t>(1, (int64_t{1} << 16) / cols), [&](int64_t begin, int64_t end) {
    std::vector<float> e(static_cast<size_t>(cols));
    for (int64_t r = begin; r < end; ++r) {
      uint16_t* row = data + r * cols;
      const float max = row_max(row, cols);
      const float sum = exp_and_sum(row, cols, max, factor, e.data());
      scale_to_bf16(e.data(), cols, 1.0f / sum, row);
    }
  });
}

}  // namespace u3d::nn
