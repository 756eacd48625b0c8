#pragma once
// torch's typed storage classes as torch.save names them in a checkpoint's pickle (torch.FloatStorage,
// torch.HalfStorage, ...) and the dtypes they hold: one table for the `.pth` reader and writer.
#include <c10/core/ScalarType.h>

#include <array>
#include <optional>
#include <string_view>
#include <utility>

namespace u3d::nn {

inline constexpr std::array<std::pair<std::string_view, c10::ScalarType>, 10> kTorchStorages = {{
    {"FloatStorage", c10::kFloat},
    {"DoubleStorage", c10::kDouble},
    {"HalfStorage", c10::kHalf},
    {"BFloat16Storage", c10::kBFloat16},
    {"LongStorage", c10::kLong},
    {"IntStorage", c10::kInt},
    {"ShortStorage", c10::kShort},
    {"CharStorage", c10::kChar},
    {"ByteStorage", c10::kByte},
    {"BoolStorage", c10::kBool},
}};

// The dtype of the storage class `name` ("FloatStorage"); nullopt for any other name.
inline std::optional<c10::ScalarType> storage_dtype(std::string_view name) {
  for (const auto& [storage, dtype] : kTorchStorages)
    if (storage == name) return dtype;
  return std::nullopt;
}

// The storage class that holds `dtype`; empty when torch has none.
inline std::string_view storage_name(c10::ScalarType dtype) {
  for (const auto& [storage, type] : kTorchStorages)
    if (type == dtype) return storage;
  return {};
}

}  // namespace u3d::nn
