// The arithmetic ceiling the networks run against: fp32 FMA and bf16 dot-product (avx512_bf16
// vdpbf16ps) throughput in GFLOP/s, on one core and on every core at once, from register-only loops
// with enough independent accumulators to hide the latency. A network's time cannot go below its FLOP
// count divided by the all-core figure; docs/networks.md ("Speed") compares the UNet against it.
// Usage: bench_cpu_peak
#include <immintrin.h>
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <initializer_list>

namespace {

constexpr long kIterations = 100'000'000;
constexpr int kAccumulators = 24;

// Sum of the lanes (a plain store: GCC 12 warns inside _mm512_reduce_add_ps).
__attribute__((target("avx512f"))) float lane_sum(__m512 v) {
  float lanes[16];
  _mm512_storeu_ps(lanes, v);
  float sum = 0;
  for (float x : lanes) sum += x;
  return sum;
}

__attribute__((target("avx512f"))) double fp32_fma_flops() {
  __m512 acc[kAccumulators];
  for (auto& a : acc) a = _mm512_set1_ps(1.0f);
  __m512 x = _mm512_set1_ps(1e-8f);
  for (long i = 0; i < kIterations; ++i) {
#pragma GCC unroll 24
    for (int k = 0; k < kAccumulators; ++k) acc[k] = _mm512_fmadd_ps(acc[k], x, x);
    __asm__ volatile("" : "+v"(x));  // keeps the loop from being folded
  }
  float sink = 0;
  for (auto& a : acc) sink += lane_sum(a);
  __asm__ volatile("" ::"x"(sink));
  return double(kIterations) * kAccumulators * 16 * 2;
}

__attribute__((target("avx512f,avx512bf16"))) double bf16_dot_flops() {
  __m512 acc[kAccumulators];
  for (auto& a : acc) a = _mm512_setzero_ps();
  __m512bh a = (__m512bh)_mm512_set1_epi16(0x3f80), b = a;  // bf16 1.0
  for (long i = 0; i < kIterations; ++i) {
#pragma GCC unroll 24
    for (int k = 0; k < kAccumulators; ++k) acc[k] = _mm512_dpbf16_ps(acc[k], a, b);
    __asm__ volatile("" : "+v"(a));
  }
  float sink = 0;
  for (auto& x : acc) sink += lane_sum(x);
  __asm__ volatile("" ::"x"(sink));
  return double(kIterations) * kAccumulators * 32 * 2;  // 32 bf16 products and sums per instruction
}

template <class F>
void report(const char* name, F kernel) {
  for (int threads : {1, omp_get_max_threads()}) {
    const auto start = std::chrono::steady_clock::now();
    double flops = 0;
#pragma omp parallel num_threads(threads) reduction(+ : flops)
    flops += kernel();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%-22s %2d thread%s  %7.1f GFLOP/s\n", name, threads, threads == 1 ? " " : "s", flops / seconds / 1e9);
  }
}

}  // namespace

int main() {
  if (!__builtin_cpu_supports("avx512f")) {
    std::printf("this CPU has no AVX-512: nothing to measure\n");
    return 0;
  }
  report("fp32 FMA (avx512f)", fp32_fma_flops);
  if (__builtin_cpu_supports("avx512bf16"))
    report("bf16 dot (avx512_bf16)", bf16_dot_flops);
  else
    std::printf("no avx512_bf16: bf16 networks are emulated and slower than fp32 here\n");
  return 0;
}
