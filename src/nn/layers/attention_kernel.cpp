#include "nn/layers/attention_kernel.h"

#include "nn/layers/vector_math.h"
#include "nn/precision.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>
#include <vector>

namespace u3d::nn {

namespace {

using namespace vector_math;

constexpr int64_t kQueryTile = 2 * kWidth;  // queries a tile: one lane each, two vectors
constexpr int64_t kKeyBlock = 64;           // keys a block of the online softmax
constexpr int64_t kRows = 8;                // keys (q·kᵀ) or channels (p·v) a register block
constexpr int64_t kMaxHeadDim = 256;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

// One head's work: `queries` query rows from q (row stride q_stride elements), written to out (row
// stride out_stride), against its packed keys and values (pack_keys, pack_values). `Element` is float
// or uint16_t (bf16 bits).
template <class Element>
struct HeadPass {
  const Element* q;
  int64_t q_stride;
  Element* out;
  int64_t out_stride;
  int64_t queries, keys, dim;
  const Element* keys_packed;  // [padded keys][dim], zero rows after the last key
  const void* values_packed;   // fp32: float [padded keys][dim]; bf16: uint32_t [padded keys / 2][dim]
  float log2_scale;  // the attention scale times log2(e): exp(scale·s) = 2^(log2_scale·s)
  // Scratch: q_tile [dim][kQueryTile] (fp32) or [dim / 2][kQueryTile] (bf16 pairs), scores
  // [kKeyBlock][kQueryTile], probability pairs [kKeyBlock / 2][kQueryTile] (bf16), accumulator
  // [dim][kQueryTile].
  uint32_t* q_tile;
  float* scores;
  uint32_t* probability_pairs;
  float* accumulator;
};

U3D_INLINE u32x16 load_u32(const uint32_t* p) {
  u32x16 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

U3D_INLINE void store_u32(uint32_t* p, u32x16 v) { std::memcpy(p, &v, sizeof v); }

U3D_INLINE f32x16 vmax(f32x16 a, f32x16 b) { return a > b ? a : b; }

// acc + a[0]·b[0] + a[1]·b[1] for each lane's pair of bf16 values (vdpbf16ps). Inline assembly rather
// than the intrinsic: the intrinsic cannot be inlined into the shared kernel body, which has no target
// of its own; only the avx512_bf16 entry point (attend_bf16) ever reaches this.
U3D_INLINE f32x16 dot_pairs(f32x16 acc, u32x16 a, u32x16 b) {
  __asm__("vdpbf16ps %2, %1, %0" : "+v"(acc) : "v"(a), "v"(b));
  return acc;
}

// 2^x for x <= 0 (relative error about 2.4e-7): x = n + f with n an integer (rounded by adding and
// subtracting 1.5 * 2^23, whose low mantissa bits then hold n) and |f| <= 1/2, 2^f by a degree-5
// polynomial (a near-minimax fit of ours on [-1/2, 1/2]), 2^n added to its exponent bits. Below -125
// the result is about 2^-125 rather than smaller (no subnormals; for -inf too): weights that small
// change no softmax. NaN stays NaN. About half the operations of exp_nonpositive (vector_math.h), whose
// cost beside the two products of 40-channel heads is not small.
U3D_INLINE f32x16 exp2_nonpositive(f32x16 x) {
  constexpr float kRound = 12582912.0f;  // 1.5 * 2^23
  x = x < -125.0f ? splat(-125.0f) : x;
  const f32x16 t = x + kRound;
  const f32x16 f = x - (t - kRound);
  f32x16 p = splat(1.3276428e-3f);
  p = p * f + 9.6755270e-3f;
  p = p * f + 5.5507131e-2f;
  p = p * f + 2.4022120e-1f;
  p = p * f + 6.9314694e-1f;
  p = p * f + 1.0f;
  return std::bit_cast<f32x16>(std::bit_cast<i32x16>(p) + (std::bit_cast<i32x16>(t) << 23));
}

// 2^x for the bf16 path's probabilities, x <= 0 (relative error about 2.7e-6, a thousandth of the bf16
// rounding that follows): x = n + f with n rounded by vrndscaleps and |f| <= 1/2, 2^f by a degree-4
// polynomial (a near-minimax fit of ours on [-1/2, 1/2]), scaled by 2^n with vscalefps, which goes to 0
// below the smallest numbers instead of wrapping: no clamp. AVX-512 only (inline assembly, as dot_pairs).
U3D_INLINE f32x16 exp2_bf16_path(f32x16 x) {
  f32x16 n, scaled;
  __asm__("vrndscaleps $0, %1, %0" : "=v"(n) : "v"(x));
  const f32x16 f = x - n;
  f32x16 p = splat(9.57003608e-3f);
  p = p * f + 5.59177138e-2f;
  p = p * f + 2.40247443e-1f;
  p = p * f + 6.93121850e-1f;
  p = p * f + 9.99999285e-1f;
  __asm__("vscalefps %2, %1, %0" : "=v"(scaled) : "v"(p), "v"(n));
  return scaled;
}

// Whether any lane of x is above the limit.
U3D_INLINE bool any_above(f32x16 x, float limit) {
  const auto above = std::bit_cast<std::array<uint64_t, 8>>(x > limit);
  uint64_t any = 0;
  for (uint64_t half_lanes : above) any |= half_lanes;
  return any != 0;
}

// The queries [first, first + n) of the pass into q_tile: q_tile[c][i] = q[first + i][c] (fp32), or
// the pair of channels 2c, 2c + 1 (bf16); zero for i >= n.
template <bool kBf16, class Element>
U3D_INLINE void load_query_tile(const HeadPass<Element>& pass, int64_t first, int64_t n) {
  const int64_t columns = kBf16 ? pass.dim / 2 : pass.dim;
  std::fill(pass.q_tile, pass.q_tile + columns * kQueryTile, 0u);
  for (int64_t i = 0; i < n; ++i) {
    const Element* row = pass.q + (first + i) * pass.q_stride;
    for (int64_t c = 0; c < columns; ++c) std::memcpy(pass.q_tile + c * kQueryTile + i, row + (kBf16 ? 2 * c : c), 4);
  }
}

// scores[j][i] = keys[first + j] · q_tile[.][i], unscaled, for j < n rounded up to a multiple of kRows
// (the keys past n are zero rows); max[h] takes the maximum over j < n of query lanes h·16 to h·16 + 15.
template <bool kBf16, class Element>
U3D_INLINE void block_scores(const HeadPass<Element>& pass, int64_t first, int64_t n, f32x16 max[2]) {
  const int64_t dim = pass.dim;
  for (int64_t j = 0; j < n; j += kRows) {
    const Element* key = pass.keys_packed + (first + j) * dim;
    f32x16 acc[kRows][2] = {};
    if constexpr (kBf16) {
      for (int64_t c = 0; c < dim / 2; ++c) {
        const u32x16 qa = load_u32(pass.q_tile + c * kQueryTile), qb = load_u32(pass.q_tile + c * kQueryTile + kWidth);
#pragma GCC unroll 8
        for (int64_t r = 0; r < kRows; ++r) {
          uint32_t pair;
          std::memcpy(&pair, key + r * dim + 2 * c, 4);
          const u32x16 k = u32x16{} + pair;
          acc[r][0] = dot_pairs(acc[r][0], qa, k);
          acc[r][1] = dot_pairs(acc[r][1], qb, k);
        }
      }
    } else {
      const auto* q_tile = reinterpret_cast<const float*>(pass.q_tile);
      for (int64_t c = 0; c < dim; ++c) {
        const f32x16 qa = load(q_tile + c * kQueryTile), qb = load(q_tile + c * kQueryTile + kWidth);
#pragma GCC unroll 8
        for (int64_t r = 0; r < kRows; ++r) {
          const f32x16 k = splat(key[r * dim + c]);
          acc[r][0] += k * qa;
          acc[r][1] += k * qb;
        }
      }
    }
#pragma GCC unroll 8
    for (int64_t r = 0; r < kRows; ++r) {
      store(pass.scores + (j + r) * kQueryTile, acc[r][0]);
      store(pass.scores + (j + r) * kQueryTile + kWidth, acc[r][1]);
      if (j + r < n) {
        max[0] = vmax(max[0], acc[r][0]);
        max[1] = vmax(max[1], acc[r][1]);
      }
    }
  }
}

// accumulator[c][i] += Σ_j p[j][i] · values[first + j][c] over the block's n keys: p is scores (fp32,
// overwritten with the probabilities) or probability_pairs (bf16).
template <bool kBf16, class Element>
U3D_INLINE void block_values(const HeadPass<Element>& pass, int64_t first, int64_t n) {
  const int64_t dim = pass.dim;
  for (int64_t c0 = 0; c0 < dim; c0 += kRows) {
    float* out = pass.accumulator + c0 * kQueryTile;
    f32x16 acc[kRows][2];
#pragma GCC unroll 8
    for (int64_t r = 0; r < kRows; ++r) {
      acc[r][0] = load(out + r * kQueryTile);
      acc[r][1] = load(out + r * kQueryTile + kWidth);
    }
    if constexpr (kBf16) {
      const auto* values = static_cast<const uint32_t*>(pass.values_packed) + first / 2 * dim + c0;
      for (int64_t j = 0; j < (n + 1) / 2; ++j) {
        const u32x16 pa = load_u32(pass.probability_pairs + j * kQueryTile);
        const u32x16 pb = load_u32(pass.probability_pairs + j * kQueryTile + kWidth);
#pragma GCC unroll 8
        for (int64_t r = 0; r < kRows; ++r) {
          const u32x16 v = u32x16{} + values[j * dim + r];
          acc[r][0] = dot_pairs(acc[r][0], pa, v);
          acc[r][1] = dot_pairs(acc[r][1], pb, v);
        }
      }
    } else {
      const auto* values = static_cast<const float*>(pass.values_packed) + first * dim + c0;
      for (int64_t j = 0; j < n; ++j) {
        const f32x16 pa = load(pass.scores + j * kQueryTile), pb = load(pass.scores + j * kQueryTile + kWidth);
#pragma GCC unroll 8
        for (int64_t r = 0; r < kRows; ++r) {
          const f32x16 v = splat(values[j * dim + r]);
          acc[r][0] += v * pa;
          acc[r][1] += v * pb;
        }
      }
    }
#pragma GCC unroll 8
    for (int64_t r = 0; r < kRows; ++r) {
      store(out + r * kQueryTile, acc[r][0]);
      store(out + r * kQueryTile + kWidth, acc[r][1]);
    }
  }
}

// The whole pass, tile by tile.
template <bool kBf16, class Element>
U3D_INLINE void attend(const HeadPass<Element>& shared_pass) {
  // A local copy: the vector stores (memcpy) could alias the caller's struct, so with it the loops
  // reloaded its pointers after every store.
  const HeadPass<Element> pass = shared_pass;
  const int64_t dim = pass.dim;
  for (int64_t first_query = 0; first_query < pass.queries; first_query += kQueryTile) {
    const int64_t nq = std::min(kQueryTile, pass.queries - first_query);
    load_query_tile<kBf16>(pass, first_query, nq);
    std::fill(pass.accumulator, pass.accumulator + dim * kQueryTile, 0.0f);
    // Per query: the largest unscaled score so far and the sum of exp(scale · (score - max)).
    f32x16 max_score[2] = {splat(-kInfinity), splat(-kInfinity)}, sum[2] = {};
    for (int64_t first_key = 0; first_key < pass.keys; first_key += kKeyBlock) {
      const int64_t n = std::min(kKeyBlock, pass.keys - first_key);
      f32x16 block_max[2] = {max_score[0], max_score[1]};
      block_scores<kBf16>(pass, first_key, n, block_max);
      // What the sums so far are worth at the new maximum: a half is rescaled only where some lane's
      // maximum grew (on the first block always: max_score is -inf, the factor 0); elsewhere every factor
      // is 1 exactly. Letting the maximum lag (weights up to 2^8, rescaled a few times a row) made the
      // bf16 path 5 % faster at 16,384 keys but 5 % less accurate against float64 in the tests' draws,
      // growing with the lag allowed.
      for (int h = 0; h < 2; ++h) {
        if (!any_above(block_max[h] - max_score[h], 0.0f)) continue;
        const f32x16 rescale = exp2_nonpositive((max_score[h] - block_max[h]) * pass.log2_scale);
        sum[h] *= rescale;
        max_score[h] = block_max[h];
        for (int64_t c = 0; c < dim; ++c) {
          float* row = pass.accumulator + c * kQueryTile + h * kWidth;
          store(row, load(row) * rescale);
        }
      }
      if constexpr (kBf16) {
        // Probabilities rounded to bf16 (nearest, ties away from zero), two keys a lane; the sum adds
        // the rounded values (a vdpbf16ps with ones), so the output is a weighted mean with exactly
        // the weights multiplied.
        const u32x16 ones = u32x16{} + 0x3f803f80u;  // bf16 1.0 in both halves of each lane
        const f32x16 scale = splat(pass.log2_scale);
        const float* scores = pass.scores;  // locals: the stores below could alias the pass's fields
        uint32_t* probability_pairs = pass.probability_pairs;
        for (int h = 0; h < 2; ++h) {
          const f32x16 offset = -max_score[h] * scale;
          const auto weight = [&](int64_t j) {  // 2^(scale·(score - max)) + half a bf16 step, as fp32 bits
            return std::bit_cast<u32x16>(exp2_bf16_path(load(scores + j * kQueryTile + h * kWidth) * scale + offset)) +
                   0x8000u;
          };
          for (int64_t j = 0; j < n; j += 2) {
            const u32x16 pairs = (weight(j) >> 16) | (j + 1 < n ? weight(j + 1) & 0xffff0000u : u32x16{});
            sum[h] = dot_pairs(sum[h], pairs, ones);
            store_u32(probability_pairs + j / 2 * kQueryTile + h * kWidth, pairs);
          }
        }
      } else {
        for (int64_t j = 0; j < n; ++j)
          for (int h = 0; h < 2; ++h) {
            float* row = pass.scores + j * kQueryTile + h * kWidth;
            const f32x16 p = exp2_nonpositive((load(row) - max_score[h]) * pass.log2_scale);
            sum[h] += p;
            store(row, p);
          }
      }
      block_values<kBf16>(pass, first_key, n);
    }
    // Normalise, round once (bf16: the 32 rounded values of a channel go to the first half of its
    // accumulator row, which has been read by then) and write the tile's rows.
    for (int h = 0; h < 2; ++h) sum[h] = 1.0f / sum[h];
    for (int64_t c = 0; c < dim; ++c)
      for (int h = 0; h < 2; ++h) {
        float* row = pass.accumulator + c * kQueryTile;
        const f32x16 normalised = load(row + h * kWidth) * sum[h];
        if constexpr (kBf16)
          store_bf16(reinterpret_cast<uint16_t*>(row) + h * kWidth, normalised);
        else
          store(row + h * kWidth, normalised);
      }
    for (int64_t i = 0; i < nq; ++i) {
      Element* out = pass.out + (first_query + i) * pass.out_stride;
      for (int64_t c = 0; c < dim; ++c) out[c] = reinterpret_cast<const Element*>(pass.accumulator + c * kQueryTile)[i];
    }
  }
}

U3D_VECTOR_CLONES void attend_fp32(const HeadPass<float>& pass) { attend<false>(pass); }

[[gnu::target("avx512f,avx512bw,avx512vl,avx512bf16")]] void attend_bf16(const HeadPass<uint16_t>& pass) {
  attend<true>(pass);
}

}  // namespace

bool fused_attention_applies(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v, int64_t heads) {
  if (q.dim() != 3 || k.dim() != 3 || v.dim() != 3 || heads < 1 || q.size(2) % heads != 0) return false;
  const torch::ScalarType type = q.scalar_type();
  if (k.scalar_type() != type || v.scalar_type() != type || !q.device().is_cpu() || !k.device().is_cpu() ||
      !v.device().is_cpu())
    return false;
  if (type != torch::kFloat && !(type == torch::kBFloat16 && cpu_has_bf16_kernels())) return false;
  const int64_t dim = q.size(2) / heads;
  return dim % kRows == 0 && dim <= kMaxHeadDim && q.size(1) > 0 && k.size(1) > 0 && k.sizes() == v.sizes() &&
         k.size(0) == q.size(0) && k.size(2) == q.size(2);
}

torch::Tensor fused_attention(const torch::Tensor& q_in, const torch::Tensor& k_in, const torch::Tensor& v_in,
                              int64_t heads, double scale) {
  TORCH_CHECK(fused_attention_applies(q_in, k_in, v_in, heads), "fused_attention: inputs it does not take");
  TORCH_CHECK(scale > 0.0, "fused_attention: the scale must be positive");
  const auto channels_contiguous = [](const torch::Tensor& x) { return x.stride(2) == 1 ? x : x.contiguous(); };
  const torch::Tensor q = channels_contiguous(q_in), k = channels_contiguous(k_in), v = channels_contiguous(v_in);
  const bool bf16 = q.scalar_type() == torch::kBFloat16;
  const int64_t batch = q.size(0), lq = q.size(1), lk = k.size(1), dim = q.size(2) / heads;
  const int64_t padded_keys = (lk + kKeyBlock - 1) / kKeyBlock * kKeyBlock;
  torch::Tensor out = torch::empty({batch, lq, heads * dim}, q.options());

  // Tasks: one sample's head, or a range of its query tiles where there are fewer heads than threads
  // to keep busy. Each task packs its head's keys and values once, into buffers of its thread.
  const int64_t tiles = (lq + kQueryTile - 1) / kQueryTile;
  const int64_t wanted_tasks = 4 * static_cast<int64_t>(at::get_num_threads());
  const int64_t parts = std::clamp<int64_t>((wanted_tasks + batch * heads - 1) / (batch * heads), 1, tiles);
  const int64_t tiles_per_part = (tiles + parts - 1) / parts;
  const int64_t element_size = bf16 ? 2 : 4;
  const auto* q_data = static_cast<const uint8_t*>(q.data_ptr());
  const auto* k_data = static_cast<const uint8_t*>(k.data_ptr());
  const auto* v_data = static_cast<const uint8_t*>(v.data_ptr());
  auto* out_data = static_cast<uint8_t*>(out.data_ptr());
  at::parallel_for(0, batch * heads * parts, 1, [&](int64_t begin, int64_t end) {
    std::vector<uint32_t> keys_packed(static_cast<size_t>(padded_keys * dim * element_size / 4));
    std::vector<uint32_t> values_packed(static_cast<size_t>(padded_keys * dim * element_size / 4));
    std::vector<uint32_t> q_tile(static_cast<size_t>(dim * kQueryTile));
    std::vector<float> scores(static_cast<size_t>(kKeyBlock * kQueryTile));
    std::vector<uint32_t> probability_pairs(static_cast<size_t>(kKeyBlock / 2 * kQueryTile));
    std::vector<float> accumulator(static_cast<size_t>(dim * kQueryTile));
    int64_t packed_head = -1;
    for (int64_t task = begin; task < end; ++task) {
      const int64_t head_index = task / parts, part = task % parts;
      const int64_t sample = head_index / heads, head = head_index % heads;
      const int64_t first_query = part * tiles_per_part * kQueryTile;
      if (first_query >= lq) continue;
      const int64_t queries = std::min(tiles_per_part * kQueryTile, lq - first_query);
      const int64_t channel = head * dim;
      if (packed_head != head_index) {
        // Keys as they are, one row per key; values as they are (fp32) or with the rows of each pair of
        // keys interleaved channel by channel (bf16: one lane of vdpbf16ps holds v[2j][c], v[2j+1][c]).
        auto* keys = reinterpret_cast<uint8_t*>(keys_packed.data());
        std::fill(keys_packed.begin(), keys_packed.end(), 0u);
        std::fill(values_packed.begin(), values_packed.end(), 0u);
        for (int64_t j = 0; j < lk; ++j) {
          const int64_t offset = (sample * k.stride(0) + j * k.stride(1) + channel) * element_size;
          std::memcpy(keys + j * dim * element_size, k_data + offset, static_cast<size_t>(dim * element_size));
        }
        for (int64_t j = 0; j < lk; ++j) {
          const uint8_t* row = v_data + (sample * v.stride(0) + j * v.stride(1) + channel) * element_size;
          if (bf16) {
            auto* pairs = reinterpret_cast<uint16_t*>(values_packed.data()) + (j / 2 * dim * 2 + j % 2);
            for (int64_t c = 0; c < dim; ++c) std::memcpy(pairs + 2 * c, row + 2 * c, 2);
          } else {
            std::memcpy(reinterpret_cast<float*>(values_packed.data()) + j * dim, row, static_cast<size_t>(dim * 4));
          }
        }
        packed_head = head_index;
      }
      const int64_t q_offset = sample * q.stride(0) + first_query * q.stride(1) + channel;
      const int64_t out_offset = (sample * lq + first_query) * heads * dim + channel;
      const auto pass_for = [&](auto* element) {
        using Element = std::remove_cv_t<std::remove_pointer_t<decltype(element)>>;
        return HeadPass<Element>{reinterpret_cast<const Element*>(q_data) + q_offset,
                                 q.stride(1),
                                 reinterpret_cast<Element*>(out_data) + out_offset,
                                 heads * dim,
                                 queries,
                                 lk,
                                 dim,
                                 reinterpret_cast<const Element*>(keys_packed.data()),
                                 values_packed.data(),
                                 static_cast<float>(scale * 1.4426950408889634),
                                 q_tile.data(),
                                 scores.data(),
                                 probability_pairs.data(),
                                 accumulator.data()};
      };
      if (bf16)
        attend_bf16(pass_for(static_cast<uint16_t*>(nullptr)));
      else
        attend_fp32(pass_for(static_cast<float*>(nullptr)));
    }
  });
  return out;
}

}  // namespace u3d::nn
