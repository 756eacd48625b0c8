#pragma once
// Building blocks of the hand-written CPU kernels (group_norm_kernel.cpp, softmax_kernel.cpp). Values
// go 16 floats at a time in GCC vector types, which each target_clones copy of a kernel
// (U3D_VECTOR_CLONES: AVX-512, AVX2, baseline; the loader picks the widest the CPU runs) lowers to its
// own registers: the exp polynomial with its selects did not auto-vectorise as scalar code. No calls
// into libm, integer and float arithmetic only.
#include <bit>
#include <cstdint>
#include <cstring>

// The helpers below take and return 64-byte vectors; they are always inlined into the kernels, so the
// calling convention GCC warns about (-Wpsabi: it differs without AVX-512) is never used.
#pragma GCC diagnostic ignored "-Wpsabi"

#define U3D_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#define U3D_INLINE [[gnu::always_inline]] inline

namespace u3d::nn::vector_math {

constexpr int64_t kWidth = 16;
using f32x16 = float __attribute__((vector_size(64)));
using i32x16 = int32_t __attribute__((vector_size(64)));
using u32x16 = uint32_t __attribute__((vector_size(64)));
using u16x16 = uint16_t __attribute__((vector_size(32)));

// v in every lane, as a bare broadcast. (Written as 0 + v it cost the fp32 attention loops a scalar add
// before each broadcast key: 0 + v is +0 for v = -0, so the compiler may not drop the add.)
U3D_INLINE f32x16 splat(float v) {
  const f32x16 first = {v};
  return __builtin_shufflevector(first, first, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
}

U3D_INLINE f32x16 load_bf16(const uint16_t* p) {
  u16x16 h;
  std::memcpy(&h, p, sizeof h);
  return std::bit_cast<f32x16>(__builtin_convertvector(h, u32x16) << 16);
}

U3D_INLINE f32x16 load(const float* p) {
  f32x16 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

U3D_INLINE void store(float* p, f32x16 v) { std::memcpy(p, &v, sizeof v); }

// Round to nearest, ties to even (NaN stays a quiet NaN), as c10::BFloat16 does.
U3D_INLINE void store_bf16(uint16_t* p, f32x16 f) {
  const u32x16 u = std::bit_cast<u32x16>(f);
  u32x16 rounded = (u + 0x7fffu + ((u >> 16) & 1u)) >> 16;
  rounded = f != f ? u32x16{} + 0x7fc0u : rounded;
  const u16x16 h = __builtin_convertvector(rounded, u16x16);
  std::memcpy(p, &h, sizeof h);
}

// The first n < 16 bf16 values at x, the other lanes `fill`.
U3D_INLINE f32x16 load_bf16_tail(const uint16_t* x, int64_t n, uint16_t fill) {
  uint16_t padded[kWidth];
  for (int64_t i = 0; i < kWidth; ++i) padded[i] = i < n ? x[i] : fill;
  return load_bf16(padded);
}

U3D_INLINE float horizontal_sum(f32x16 v) {
  float s = 0.0f;
  for (int64_t j = 0; j < kWidth; ++j) s += v[j];
  return s;
}

U3D_INLINE float bf16_to_float(uint16_t v) { return std::bit_cast<float>(static_cast<uint32_t>(v) << 16); }

// Element access for kernels written once for bf16 (its 16 bits; rounded once on the way out) and fp32.
U3D_INLINE float to_float(uint16_t v) { return bf16_to_float(v); }
U3D_INLINE float to_float(float v) { return v; }
U3D_INLINE f32x16 load_values(const uint16_t* p) { return load_bf16(p); }
U3D_INLINE f32x16 load_values(const float* p) { return load(p); }
U3D_INLINE void store_values(uint16_t* p, f32x16 v) { store_bf16(p, v); }
U3D_INLINE void store_values(float* p, f32x16 v) { store(p, v); }

// exp(x) for x <= 0 (relative error about 1e-7): x = n ln 2 + r with n an integer (rounded by adding
// and subtracting 1.5 * 2^23, whose low mantissa bits then hold n) and ln 2 split in two parts
// (Cody-Waite), exp(r) by the degree-6 minimax polynomial of the Cephes library's expf, and 2^n built
// in the exponent bits. Below ln(FLT_MIN) the result would be subnormal; it is 0 there (also for -inf).
U3D_INLINE f32x16 exp_nonpositive(f32x16 x) {
  constexpr float kLowest = -87.33654f;  // ln(FLT_MIN)
  constexpr float kRound = 12582912.0f;  // 1.5 * 2^23
  const i32x16 tiny = x < kLowest;
  x = tiny ? splat(kLowest) : x;
  const f32x16 t = x * 1.44269504088896341f + kRound;
  const f32x16 n = t - kRound;
  const f32x16 r = x - n * 0.693359375f + n * 2.12194440e-4f;
  f32x16 p = splat(1.9875691500e-4f);
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  const i32x16 exponent = std::bit_cast<i32x16>(t) - std::bit_cast<int32_t>(kRound) + 127;
  return tiny ? f32x16{} : p * std::bit_cast<f32x16>(exponent << 23);
}

}  // namespace u3d::nn::vector_math
