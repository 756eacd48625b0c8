// The arithmetic ceiling the networks run against: fp32 FMA and bf16 dot-product (avx512_bf16
// vdpbf16ps) throughput in GFLOP/s, on one core and on every core at once, from register-only loops
// with enough independent accumulators to hide the latency; on CPUs with AMX (Intel Xeon since
// Sapphire Rapids) also the bf16 tile product (tdpbf16ps), which oneDNN's bf16 kernels use there, so
// that is the bf16 ceiling of such a host. A network's time cannot go below its FLOP
// count divided by the all-core figure; docs/networks.md ("Speed") compares the UNet against it.
// Usage: bench_cpu_peak
#include <cpuid.h>
#include <immintrin.h>
#include <omp.h>
#include <sys/syscall.h>
#include <unistd.h>

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

// AMX: CPUID leaf 7 EDX bits 22 (AMX-BF16) and 24 (AMX-TILE), and the kernel's permission to use the
// tile data (Linux asks each process to request it: arch_prctl ARCH_REQ_XCOMP_PERM for XTILEDATA).
bool amx_bf16_usable() {
  unsigned eax, ebx, ecx, edx;
  if (!__get_cpuid_count(7, 0, &eax, &ebx, &ecx, &edx)) return false;
  if (!((edx >> 22) & 1) || !((edx >> 24) & 1)) return false;
  constexpr long kArchReqXcompPerm = 0x1023, kXfeatureXtiledata = 18;
  return syscall(SYS_arch_prctl, kArchReqXcompPerm, kXfeatureXtiledata) == 0;
}

// Four 16x16 fp32 accumulator tiles, each step adding the products of two 16x32 bf16 tiles with two
// 16x(2x16) ones: 4 tdpbf16ps of 16 * 16 * 32 products and sums each.
__attribute__((target("amx-tile,amx-bf16"))) double amx_bf16_flops() {
  struct alignas(64) {
    uint8_t palette = 1, start_row = 0, reserved[14] = {};
    uint16_t colsb[16] = {};
    uint8_t rows[16] = {};
  } config;
  for (int t = 0; t < 8; ++t) config.colsb[t] = 64, config.rows[t] = 16;
  _tile_loadconfig(&config);
  alignas(64) static thread_local uint16_t ones[16 * 32];
  for (uint16_t& x : ones) x = 0x3c00;  // bf16 2^-7: the sums stay finite
  alignas(64) static thread_local float out[16 * 16];
  _tile_zero(0);
  _tile_zero(1);
  _tile_zero(2);
  _tile_zero(3);
  _tile_loadd(4, ones, 64);
  _tile_loadd(5, ones, 64);
  _tile_loadd(6, ones, 64);
  _tile_loadd(7, ones, 64);
  constexpr long kTileIterations = kIterations / 16;
  for (long i = 0; i < kTileIterations; ++i) {
    _tile_dpbf16ps(0, 4, 6);
    _tile_dpbf16ps(1, 4, 7);
    _tile_dpbf16ps(2, 5, 6);
    _tile_dpbf16ps(3, 5, 7);
  }
  _tile_stored(0, out, 64);
  _tile_release();
  __asm__ volatile("" ::"r"(out[0]));
  return double(kTileIterations) * 4 * 16 * 16 * 32 * 2;
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
  if (amx_bf16_usable()) report("bf16 tiles (amx_bf16)", amx_bf16_flops);
  return 0;
}
