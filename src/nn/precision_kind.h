#pragma once
// The precision a network runs in, as a plain value: callers that only choose it (the library facade,
// the command's --dtype) include this without libtorch. What each choice means, and the conversion of
// a model, are in nn/precision.h.
#include <string>

namespace u3d::nn {

enum class Precision { kFp32, kBf16, kFp16 };

// "fp32" | "bf16" | "fp16"; anything else is an Error naming `what` and the choices.
Precision parse_precision(const std::string& text, const std::string& what);
const char* precision_name(Precision precision);

}  // namespace u3d::nn
