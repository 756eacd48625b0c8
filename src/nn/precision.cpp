#include "nn/precision.h"

#include <utility>
#include <vector>

#include "core/error.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

Precision parse_precision(const std::string& text, const std::string& what) {
  if (text == "fp32") return Precision::kFp32;
  if (text == "bf16") return Precision::kBf16;
  if (text == "fp16") return Precision::kFp16;
  throw Error(what + ": unknown precision '" + text + "' (choose fp32, bf16 or fp16)");
}

const char* precision_name(Precision precision) {
  switch (precision) {
    case Precision::kBf16:
      return "bf16";
    case Precision::kFp16:
      return "fp16";
    case Precision::kFp32:
      break;
  }
  return "fp32";
}

torch::ScalarType scalar_type(Precision precision) {
  switch (precision) {
    case Precision::kBf16:
      return torch::kBFloat16;
    case Precision::kFp16:
      return torch::kHalf;
    case Precision::kFp32:
      break;
  }
  return torch::kFloat;
}

bool cpu_has_bf16_kernels() {
  return __builtin_cpu_supports("avx512bf16") && __builtin_cpu_supports("avx512f") &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
}

Precision default_precision(const torch::Device& device) {
  if (device.is_cuda()) return Precision::kFp16;
  return cpu_has_bf16_kernels() ? Precision::kBf16 : Precision::kFp32;
}

void check_precision_supported(Precision precision, const torch::Device& device) {
  if (precision == Precision::kFp16 && !device.is_cuda())
    throw Error("fp16 runs on CUDA only; on the CPU use bf16 (fast on CPUs with avx512_bf16) or fp32");
}

namespace {

// Calls convert(tensor, type) for every floating parameter (is_parameter) and buffer of `model`, with the
// type it has in `precision`: the model's type, fp32 in GroupNorm and LayerNorm.
template <class Convert>
void for_each_floating_tensor(torch::nn::Module& model, Precision precision, Convert convert) {
  torch::NoGradGuard no_grad;
  const torch::ScalarType model_type = scalar_type(precision);
  for (const auto& module : model.modules(/*include_self=*/true)) {
    const bool norm = dynamic_cast<GroupNormImpl*>(module.get()) || dynamic_cast<LayerNormImpl*>(module.get());
    const torch::ScalarType type = norm ? torch::kFloat : model_type;
    for (auto& p : module->named_parameters(/*recurse=*/false))
      if (p.value().is_floating_point()) convert(p.value(), type, /*is_parameter=*/true);
    for (auto& b : module->named_buffers(/*recurse=*/false))
      if (b.value().is_floating_point()) convert(b.value(), type, /*is_parameter=*/false);
  }
}

}  // namespace

void set_precision(torch::nn::Module& model, Precision precision) {
  for_each_floating_tensor(model, precision,
                           [](torch::Tensor& t, torch::ScalarType type, bool) { t.set_data(t.to(type)); });
}

void allocate_in_precision(torch::nn::Module& model, Precision precision) {
  std::vector<std::pair<torch::Tensor, torch::ScalarType>> parameters;
  for_each_floating_tensor(model, precision, [&](torch::Tensor& t, torch::ScalarType type, bool is_parameter) {
    // A buffer may hold what the model computed when it was built (a checkpoint may lack it).
    if (is_parameter)
      parameters.emplace_back(t, type);
    else
      t.set_data(t.to(type));
  });
  if (parameters.empty()) return;
  // One block for all: one mapping with large pages (nn/tensor_allocator.h) instead of thousands of
  // small allocations whose pages are faulted in one by one as the checkpoint is copied in.
  constexpr int64_t kAlign = 64;
  auto bytes_of = [](const std::pair<torch::Tensor, torch::ScalarType>& p) {
    return (p.first.numel() * int64_t(c10::elementSize(p.second)) + kAlign - 1) / kAlign * kAlign;
  };
  int64_t total = 0;
  for (const auto& p : parameters) total += bytes_of(p);
  const torch::Tensor block = torch::empty({total}, parameters.front().first.options().dtype(torch::kByte));
  int64_t offset = 0;
  for (auto& p : parameters) {
    auto& [t, type] = p;
    t.set_data(torch::empty({0}, t.options().dtype(type))
                   .set_(block.storage(), offset / int64_t(c10::elementSize(type)), t.sizes()));
    offset += bytes_of(p);
  }
}

}  // namespace u3d::nn
