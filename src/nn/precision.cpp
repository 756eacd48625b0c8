#include "nn/precision.h"

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

void set_precision(torch::nn::Module& model, Precision precision) {
  torch::NoGradGuard no_grad;
  const torch::ScalarType model_type = scalar_type(precision);
  for (const auto& module : model.modules(/*include_self=*/true)) {
    const bool norm = dynamic_cast<GroupNormImpl*>(module.get()) || dynamic_cast<LayerNormImpl*>(module.get());
    const torch::ScalarType type = norm ? torch::kFloat : model_type;
    for (auto& p : module->named_parameters(/*recurse=*/false))
      if (p.value().is_floating_point()) p.value().set_data(p.value().to(type));
    for (auto& b : module->named_buffers(/*recurse=*/false))
      if (b.value().is_floating_point()) b.value().set_data(b.value().to(type));
  }
}

}  // namespace u3d::nn
