#include "nn/layers/group_norm_kernel.h"

#include "nn/layers/vector_math.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

namespace u3d::nn {

namespace {

using namespace vector_math;

// Pixels per block of the statistics: each block's channel sums are accumulated in fp32.
constexpr int64_t kBlockPixels = 256;

// x * sigmoid(x), with exp of -|x| only (no overflow): sigmoid(x) = 1 / (1 + e) for x >= 0 and
// e / (1 + e) for x < 0, where e = exp(-|x|).
U3D_INLINE f32x16 silu(f32x16 x) {
  const f32x16 magnitude = std::bit_cast<f32x16>(std::bit_cast<u32x16>(x) & 0x7fffffffu);
  const f32x16 e = exp_nonpositive(-magnitude);
  return x * ((x >= 0.0f ? splat(1.0f) : e) / (1.0f + e));
}

// Adds each pixel's values (mean == nullptr) or squared deviations from `mean` to the channel sums, 16
// channels at a time in explicit vectors and the last ones of a pixel through a padded copy: every
// channel goes through the same instructions wherever the data lies. (Left to the auto-vectoriser, which
// of its full-width, half-width and scalar loops a channel took depended on the addresses, and they
// rounded differently, fused multiply-add against a product then a sum: the same input gave results
// that differed in the last bit from one call to the next.)
template <class T>
U3D_INLINE void accumulate_pixels_of(const T* x, int64_t pixels, int64_t channels, const float* mean, float* sums) {
  const int64_t full = channels / kWidth * kWidth, rest = channels - full;
  const auto term = [mean](f32x16 v, const float* m, int64_t c) {
    if (!mean) return v;
    const f32x16 d = v - load(m + c);
    return d * d;
  };
  float tail_mean[kWidth] = {}, tail_sums[kWidth] = {};
  if (mean) std::copy(mean + full, mean + channels, tail_mean);
  std::copy(sums + full, sums + channels, tail_sums);
  for (int64_t p = 0; p < pixels; ++p) {
    const T* row = x + p * channels;
    for (int64_t c = 0; c < full; c += kWidth) store(sums + c, load(sums + c) + term(load_values(row + c), mean, c));
    if (rest) {
      T values[kWidth] = {};
      std::copy(row + full, row + channels, values);
      store(tail_sums, load(tail_sums) + term(load_values(values), tail_mean, 0));
    }
  }
  std::copy(tail_sums, tail_sums + rest, sums + full);
}

// y = x * scale + shift per channel, then SiLU if asked; 16 channels at a time, the last ones of a pixel
// through a padded copy.
U3D_INLINE f32x16 scale_shift(f32x16 v, const float* scale, const float* shift, bool apply_silu) {
  v = v * load(scale) + load(shift);
  return apply_silu ? silu(v) : v;
}

template <class T>
U3D_INLINE void scale_pixels_of(const T* x, int64_t pixels, int64_t channels, const float* scale, const float* shift,
                                bool apply_silu, T* y) {
  const int64_t full = channels / kWidth * kWidth;
  for (int64_t p = 0; p < pixels; ++p) {
    const T* in = x + p * channels;
    T* out = y + p * channels;
    for (int64_t c = 0; c < full; c += kWidth)
      store_values(out + c, scale_shift(load_values(in + c), scale + c, shift + c, apply_silu));
    if (full < channels) {
      T values[kWidth] = {}, results[kWidth];
      float s[kWidth] = {}, t[kWidth] = {};
      std::copy(in + full, in + channels, values);
      std::copy(scale + full, scale + channels, s);
      std::copy(shift + full, shift + channels, t);
      store_values(results, scale_shift(load_values(values), s, t, apply_silu));
      std::copy(results, results + (channels - full), out + full);
    }
  }
}

// One copy per instruction set of each kernel and input type (target_clones on plain functions).
#define U3D_GROUP_NORM_KERNELS(T)                                                                                \
  U3D_VECTOR_CLONES void add_pixels(const T* x, int64_t pixels, int64_t channels, float* sums) {                 \
    accumulate_pixels_of(x, pixels, channels, nullptr, sums);                                                                    \
  }                                                                                                              \
  U3D_VECTOR_CLONES void add_squared_deviations(const T* x, int64_t pixels, int64_t channels, const float* mean, \
                                                float* sums) {                                                   \
    accumulate_pixels_of(x, pixels, channels, mean, sums);                                                  \
  }                                                                                                              \
  U3D_VECTOR_CLONES void scale_pixels(const T* x, int64_t pixels, int64_t channels, const float* scale,          \
                                      const float* shift, bool apply_silu, T* y) {                               \
    scale_pixels_of(x, pixels, channels, scale, shift, apply_silu, y);                                           \
  }
U3D_GROUP_NORM_KERNELS(uint16_t)
U3D_GROUP_NORM_KERNELS(float)
#undef U3D_GROUP_NORM_KERNELS

template <class T>
torch::Tensor group_norm_of(const torch::Tensor& x, int64_t groups, const torch::Tensor& weight,
                            const torch::Tensor& bias, double eps, bool silu) {
  const int64_t batch = x.size(0), channels = x.size(1), pixels = x.size(2) * x.size(3);
  const int64_t per_group = channels / groups;
  const int64_t blocks = std::max<int64_t>((pixels + kBlockPixels - 1) / kBlockPixels, 1);
  const auto* in = reinterpret_cast<const T*>(x.data_ptr());
  torch::Tensor y = torch::empty_like(x);
  auto* out = reinterpret_cast<T*>(y.data_ptr());
  const torch::Tensor w = weight.contiguous(), b = bias.contiguous();
  const float* gamma = w.data_ptr<float>();
  const float* beta = b.data_ptr<float>();

  // Each (sample, block of pixels) task sums its pixels per channel into its own row.
  std::vector<float> partial(static_cast<size_t>(batch * blocks * channels));
  const auto for_each_block = [&](auto&& body) {
    at::parallel_for(0, batch * blocks, 1, [&](int64_t begin, int64_t end) {
      for (int64_t task = begin; task < end; ++task) {
        const int64_t n = task / blocks, first = task % blocks * kBlockPixels;
        body(n, in + (n * pixels + first) * channels, std::min(kBlockPixels, pixels - first),
             partial.data() + task * channels);
      }
    });
  };
  // Per sample and group: the sum of the blocks' channel sums over the group's channels, in double.
  const auto group_totals = [&](int64_t n, std::vector<double>& totals) {
    std::fill(totals.begin(), totals.end(), 0.0);
    for (int64_t block = 0; block < blocks; ++block) {
      const float* row = partial.data() + (n * blocks + block) * channels;
      for (int64_t c = 0; c < channels; ++c) totals[c / per_group] += row[c];
    }
  };

  std::fill(partial.begin(), partial.end(), 0.0f);
  for_each_block([&](int64_t, const T* src, int64_t count, float* sums) { add_pixels(src, count, channels, sums); });
  const double count = static_cast<double>(pixels * per_group);
  std::vector<float> mean(static_cast<size_t>(batch * channels));
  std::vector<double> totals(static_cast<size_t>(groups));
  for (int64_t n = 0; n < batch; ++n) {
    group_totals(n, totals);
    for (int64_t c = 0; c < channels; ++c) mean[n * channels + c] = static_cast<float>(totals[c / per_group] / count);
  }

  // The variance from the deviations (two passes), not from E[x^2] - mean^2.
  std::fill(partial.begin(), partial.end(), 0.0f);
  for_each_block([&](int64_t n, const T* src, int64_t count_pixels, float* sums) {
    add_squared_deviations(src, count_pixels, channels, mean.data() + n * channels, sums);
  });
  std::vector<float> scale(static_cast<size_t>(batch * channels)), shift(scale.size());
  for (int64_t n = 0; n < batch; ++n) {
    group_totals(n, totals);
    for (int64_t c = 0; c < channels; ++c) {
      const double rstd = 1.0 / std::sqrt(totals[c / per_group] / count + eps);
      const double a = rstd * gamma[c];
      scale[n * channels + c] = static_cast<float>(a);
      shift[n * channels + c] = static_cast<float>(beta[c] - mean[n * channels + c] * a);
    }
  }

  for_each_block([&](int64_t n, const T* src, int64_t count_pixels, float*) {
    scale_pixels(src, count_pixels, channels, scale.data() + n * channels, shift.data() + n * channels, silu,
                 out + (src - in));
  });
  return y;
}

}  // namespace

bool group_norm_channels_last_applies(const torch::Tensor& x, const torch::Tensor& weight) {
  return x.device().is_cpu() && (x.scalar_type() == torch::kBFloat16 || x.scalar_type() == torch::kFloat) &&
         x.dim() == 4 && x.is_contiguous(at::MemoryFormat::ChannelsLast) && weight.scalar_type() == torch::kFloat &&
         weight.device().is_cpu() && weight.numel() == x.size(1);
}

torch::Tensor group_norm_channels_last(const torch::Tensor& x, int64_t groups, const torch::Tensor& weight,
                                       const torch::Tensor& bias, double eps, bool silu) {
  TORCH_CHECK(group_norm_channels_last_applies(x, weight),
              "group_norm_channels_last: not a channels-last bf16 or fp32 input");
  TORCH_CHECK(groups > 0 && x.size(1) % groups == 0, "GroupNorm: ", x.size(1), " channels do not split into ", groups,
              " groups");
  return x.scalar_type() == torch::kBFloat16 ? group_norm_of<uint16_t>(x, groups, weight, bias, eps, silu)
                                             : group_norm_of<float>(x, groups, weight, bias, eps, silu);
}

}  // namespace u3d::nn
