// multi_head_attention at the long sequences of the Unique3D networks, random inputs, every core:
// the first level of a refinement step (batch 2, 16,384 tokens, 8 heads of 40 channels) and of a
// normal-map step (batch 4, 4,096 tokens). Prints the median seconds of --repetitions (default 3)
// calls per case. --score-budget=N replaces multi_head_attention's default (kDefaultAttentionScoreBudget).
// Usage: bench_attention [--repetitions=N] [--dtype=fp32|bf16] [--score-budget=N]
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "core/error.h"
#include "nn/layers/attention.h"
#include "nn/precision.h"
#include "nn/runtime.h"

using namespace u3d::nn;

int main(int argc, char** argv) try {
  int repetitions = 3;
  Precision precision = Precision::kFp32;
  int64_t budget = kDefaultAttentionScoreBudget;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.starts_with("--repetitions="))
      repetitions = std::max(1, std::stoi(arg.substr(14)));
    else if (arg.starts_with("--score-budget="))
      budget = std::stoll(arg.substr(15));
    else if (arg.starts_with("--dtype="))
      precision = parse_precision(arg.substr(8), "--dtype");
    else
      throw u3d::Error("unknown argument '" + arg +
                       "' (usage: bench_attention [--repetitions=N] [--dtype=fp32|bf16] [--score-budget=N])");
  }
  configure_torch_threads();
  c10::InferenceMode inference;
  torch::manual_seed(0);
  struct Case {
    const char* name;
    int64_t batch, tokens, channels, heads;
  };
  for (const Case& c : {Case{"refine, first level: batch 2, 16384 tokens, 320 channels, 8 heads", 2, 16384, 320, 8},
                        Case{"normal, first level: batch 4, 4096 tokens, 320 channels, 8 heads", 4, 4096, 320, 8}}) {
    const auto options = torch::TensorOptions().dtype(scalar_type(precision));
    const torch::Tensor q = torch::randn({c.batch, c.tokens, c.channels}).to(options);
    const torch::Tensor k = torch::randn({c.batch, c.tokens, c.channels}).to(options);
    const torch::Tensor v = torch::randn({c.batch, c.tokens, c.channels}).to(options);
    std::vector<double> times;
    for (int r = 0; r < repetitions; ++r) {
      const auto start = std::chrono::steady_clock::now();
      const torch::Tensor out =
          multi_head_attention(q, k, v, c.heads, 1.0 / std::sqrt(double(c.channels / c.heads)), budget);
      times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(times.begin(), times.end());
    std::printf("%-70s %s: %7.3f s\n", c.name, precision_name(precision), times[times.size() / 2]);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_attention: %s\n", e.what());
  return 1;
}
