#include "nn/layers/geglu_kernel.h"

#include "nn/layers/vector_math.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

namespace u3d::nn {

namespace {

using namespace vector_math;

// erfc(z) for z >= 0 with a relative error under 1.2e-7 everywhere (the Chebyshev fit of Numerical
// Recipes' erfcc): t = 1 / (1 + z/2), erfc(z) = t * exp(-z^2 + P(t)). The exponent is never positive,
// and erfc underflows to 0 past z = 9.
U3D_INLINE f32x16 erfc_nonnegative(f32x16 z) {
  const f32x16 t = 1.0f / (1.0f + 0.5f * z);
  f32x16 p = splat(0.17087277f);
  p = p * t - 0.82215223f;
  p = p * t + 1.48851587f;
  p = p * t - 1.13520398f;
  p = p * t + 0.27886807f;
  p = p * t - 0.18628806f;
  p = p * t + 0.09678418f;
  p = p * t + 0.37409196f;
  p = p * t + 1.00002368f;
  p = p * t - 1.26551223f;
  const f32x16 exponent = p - z * z;
  return t * exp_nonpositive(exponent < 0.0f ? exponent : f32x16{});
}

// gelu(x) = x/2 * (1 + erf(x/sqrt 2)) = x/2 * (2 - erfc(|x|/sqrt 2)) for x >= 0, x/2 * erfc(|x|/sqrt 2)
// below: no cancellation in the small negative tail.
U3D_INLINE f32x16 gelu(f32x16 x) {
  const f32x16 magnitude = std::bit_cast<f32x16>(std::bit_cast<u32x16>(x) & 0x7fffffffu);
  const f32x16 e = erfc_nonnegative(magnitude * 0.70710678118654752f);
  return 0.5f * x * (x >= 0.0f ? 2.0f - e : e);
}

// out[j] = hidden[j] * gelu(gate[j]) for j < n.
template <class T>
U3D_INLINE void gate_row_of(const T* hidden, const T* gate, int64_t n, T* out) {
  int64_t j = 0;
  for (; j + kWidth <= n; j += kWidth)
    store_values(out + j, load_values(hidden + j) * gelu(load_values(gate + j)));
  if (j < n) {
    T h[kWidth] = {}, g[kWidth] = {}, result[kWidth];
    std::copy(hidden + j, hidden + n, h);
    std::copy(gate + j, gate + n, g);
    store_values(result, load_values(h) * gelu(load_values(g)));
    std::copy(result, result + (n - j), out + j);
  }
}

U3D_VECTOR_CLONES void gate_row(const uint16_t* hidden, const uint16_t* gate, int64_t n, uint16_t* out) {
  gate_row_of(hidden, gate, n, out);
}
U3D_VECTOR_CLONES void gate_row(const float* hidden, const float* gate, int64_t n, float* out) {
  gate_row_of(hidden, gate, n, out);
}

template <class T>
void gate_rows(const torch::Tensor& projected, torch::Tensor& out, int64_t n) {
  const int64_t rows = projected.numel() / (2 * n);
  const auto* in = reinterpret_cast<const T*>(projected.data_ptr());
  auto* result = reinterpret_cast<T*>(out.data_ptr());
  at::parallel_for(0, rows, std::max<int64_t>(1, (int64_t{1} << 14) / n), [&](int64_t begin, int64_t end) {
    for (int64_t r = begin; r < end; ++r) gate_row(in + r * 2 * n, in + r * 2 * n + n, n, result + r * n);
  });
}

}  // namespace

bool geglu_applies(const torch::Tensor& projected) {
  return projected.device().is_cpu() &&
         (projected.scalar_type() == torch::kBFloat16 || projected.scalar_type() == torch::kFloat) &&
         projected.dim() >= 1 && projected.is_contiguous() && projected.size(-1) % 2 == 0;
}

torch::Tensor geglu(const torch::Tensor& projected) {
  TORCH_CHECK(geglu_applies(projected), "geglu: not a contiguous bf16 or fp32 CPU tensor with an even last dimension");
  const int64_t n = projected.size(-1) / 2;
  std::vector<int64_t> sizes = projected.sizes().vec();
  sizes.back() = n;
  torch::Tensor out = torch::empty(sizes, projected.options());
  if (n == 0) return out;
  if (projected.scalar_type() == torch::kBFloat16)
    gate_rows<uint16_t>(projected, out, n);
  else
    gate_rows<float>(projected, out, n);
  return out;
}

}  // namespace u3d::nn
