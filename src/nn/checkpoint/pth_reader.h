#pragma once
// PyTorch checkpoints in the zip format of torch.save (torch >= 1.6; also diffusers' *.bin weights),
// holding one flat state dict {name: tensor}, e.g. Unique3D's ckpt/img2mvimg/unet_state_dict.pth, or a
// dict of such state dicts, as basicsr saves them ({"params_ema": {...}}, e.g. RealESRGAN_x4plus.pth),
// whose tensors are returned as "<outer key>.<name>".
//
// The pickle is read by a restricted reader that only knows collections.OrderedDict,
// torch._utils._rebuild_tensor_v2 / _rebuild_parameter and the typed storages torch.<T>Storage
// (Float, Double, Half, BFloat16, Long, Int, Short, Char, Byte, Bool): any other global (code the
// file would run in Python) is refused. Storage offsets, strides and storages shared between tensors
// are honoured: tensors are returned as views of their (shared) storage, on the CPU, and a storage is
// a view of the file's record in the mapped file (mapped_file.h), not a copy of it.
// Every record is checked against its zip CRC-32. The legacy pre-1.6 format, truncated or corrupt
// archives, non-tensor entries and views reaching outside their storage are u3d::Error naming the
// file (and tensor).
#include <filesystem>

#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

TensorMap load_pth(const std::filesystem::path& path);

// The same file's tensor names, dtypes and shapes as tensors on the meta device (no data), with the
// structure checked as far as it can be without reading the data: the zip directory (at the end of the
// file, so a truncated download fails), the pickle, and each storage record's presence and size.
// CRCs are not checked (that needs the data).
TensorMap inspect_pth(const std::filesystem::path& path);

}  // namespace u3d::nn
