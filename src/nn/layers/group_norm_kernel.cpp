#include "nn/layers/group_norm_kernel.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

namespace u3d::nn {

namespace {

// Pixels per block of the statistics: each block's channel sums are accumulated in fp32.
constexpr int64_t kBlockPixels = 256;

// The loops below are plain C++ that the compiler vectorises; each is built for AVX-512, AVX2 and the
// baseline, and the loader picks the widest the CPU runs.
#define U3D_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))

inline float bf16_to_float(uint16_t v) { return std::bit_cast<float>(static_cast<uint32_t>(v) << 16); }

// Round to nearest, ties to even (NaN stays a quiet NaN), as c10::BFloat16 does.
inline uint16_t float_to_bf16(float f) {
  const uint32_t u = std::bit_cast<uint32_t>(f);
  return f != f ? uint16_t{0x7fc0} : static_cast<uint16_t>((u + 0x7fffu + ((u >> 16) & 1u)) >> 16);
}

// exp(x) for x <= 0 (the SiLU of negative inputs): Cody-Waite reduction by ln 2 and the degree-6
// minimax polynomial of the Cephes library's expf (relative error about 1e-7); below -87 it is 0.
inline float exp_nonpositive(float x) {
  x = std::max(x, -87.0f);
  const float n = std::nearbyint(x * 1.44269504088896341f);
  const float r = x - n * 0.693359375f + n * 2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  return p * std::bit_cast<float>((static_cast<int32_t>(n) + 127) << 23);
}

// x * sigmoid(x), with exp of -|x| only (no overflow): sigmoid(x) = 1 / (1 + e) for x >= 0 and
// e / (1 + e) for x < 0, where e = exp(-|x|).
inline float silu(float x) {
  const float e = exp_nonpositive(-std::fabs(x));
  const float s = (x >= 0.0f ? 1.0f : e) / (1.0f + e);
  return x * s;
}

U3D_VECTOR_CLONES void add_pixels(const uint16_t* x, int64_t pixels, int64_t channels, float* sums) {
  for (int64_t p = 0; p < pixels; ++p) {
    const uint16_t* row = x + p * channels;
    for (int64_t c = 0; c < channels; ++c) sums[c] += bf16_to_float(row[c]);
  }
}

U3D_VECTOR_CLONES void add_squared_deviations(const uint16_t* x, int64_t pixels, int64_t channels, const float* mean,
                                              float* sums) {
  for (int64_t p = 0; p < pixels; ++p) {
    const uint16_t* row = x + p * channels;
    for (int64_t c = 0; c < channels; ++c) {
      const float d = bf16_to_float(row[c]) - mean[c];
      sums[c] += d * d;
    }
  }
}

U3D_VECTOR_CLONES void scale_pixels(const uint16_t* x, int64_t pixels, int64_t channels, const float* scale,
                                    const float* shift, bool apply_silu, uint16_t* y) {
  for (int64_t p = 0; p < pixels; ++p) {
    const uint16_t* in = x + p * channels;
    uint16_t* out = y + p * channels;
    if (apply_silu) {
      for (int64_t c = 0; c < channels; ++c) out[c] = float_to_bf16(silu(bf16_to_float(in[c]) * scale[c] + shift[c]));
    } else {
      for (int64_t c = 0; c < channels; ++c) out[c] = float_to_bf16(bf16_to_float(in[c]) * scale[c] + shift[c]);
    }
  }
}

}  // namespace

bool group_norm_channels_last_applies(const torch::Tensor& x, const torch::Tensor& weight) {
  return x.device().is_cpu() && x.scalar_type() == torch::kBFloat16 && x.dim() == 4 &&
         x.is_contiguous(at::MemoryFormat::ChannelsLast) && weight.scalar_type() == torch::kFloat &&
         weight.device().is_cpu() && weight.numel() == x.size(1);
}

torch::Tensor group_norm_channels_last(const torch::Tensor& x, int64_t groups, const torch::Tensor& weight,
                                       const torch::Tensor& bias, double eps, bool silu) {
  TORCH_CHECK(group_norm_channels_last_applies(x, weight), "group_norm_channels_last: not a channels-last bf16 input");
  const int64_t batch = x.size(0), channels = x.size(1), pixels = x.size(2) * x.size(3);
  TORCH_CHECK(groups > 0 && channels % groups == 0, "GroupNorm: ", channels, " channels do not split into ", groups,
              " groups");
  const int64_t per_group = channels / groups;
  const int64_t blocks = std::max<int64_t>((pixels + kBlockPixels - 1) / kBlockPixels, 1);
  const auto* in = reinterpret_cast<const uint16_t*>(x.data_ptr());
  torch::Tensor y = torch::empty_like(x);
  auto* out = reinterpret_cast<uint16_t*>(y.data_ptr());
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
  for_each_block(
      [&](int64_t, const uint16_t* src, int64_t count, float* sums) { add_pixels(src, count, channels, sums); });
  const double count = static_cast<double>(pixels * per_group);
  std::vector<float> mean(static_cast<size_t>(batch * channels));
  std::vector<double> totals(static_cast<size_t>(groups));
  for (int64_t n = 0; n < batch; ++n) {
    group_totals(n, totals);
    for (int64_t c = 0; c < channels; ++c) mean[n * channels + c] = static_cast<float>(totals[c / per_group] / count);
  }

  // The variance from the deviations (two passes), not from E[x^2] - mean^2.
  std::fill(partial.begin(), partial.end(), 0.0f);
  for_each_block([&](int64_t n, const uint16_t* src, int64_t count_pixels, float* sums) {
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

  for_each_block([&](int64_t n, const uint16_t* src, int64_t count_pixels, float*) {
    scale_pixels(src, count_pixels, channels, scale.data() + n * channels, shift.data() + n * channels, silu,
                 out + (src - in));
  });
  return y;
}

}  // namespace u3d::nn
