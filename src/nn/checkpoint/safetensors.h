#pragma once
// safetensors files: 8-byte little-endian header length, JSON header {name: {dtype, shape,
// data_offsets}}, raw little-endian data. The file is memory-mapped and its tensors are views of the
// mapping (mapped_file.h), in their stored dtype (F32, F16, BF16, F64, I64, I32, U8, BOOL). Truncated
// files, overlapping or out-of-range offsets and unknown dtypes are u3d::Error naming the file and
// tensor.
#include <filesystem>

#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

TensorMap load_safetensors(const std::filesystem::path& path);

// The file's tensor names, dtypes and shapes as tensors on the meta device (no data), read from the
// header alone, with the same checks of the header and offsets (a truncated download fails here).
TensorMap inspect_safetensors(const std::filesystem::path& path);

// Writes a safetensors file (atomically); used by tests and conversion tools.
void save_safetensors(const TensorMap& tensors, const std::filesystem::path& path);

}  // namespace u3d::nn
