#pragma once
// Writes a state dict {name: tensor} in torch.save's zip format (what pth_reader.h reads, and what
// torch.load reads): a protocol-2 pickle of an OrderedDict whose tensors are rebuilt by
// torch._utils._rebuild_tensor_v2 from one storage record per tensor, little-endian. Used to make
// checkpoints in the official layout (Unique3D's unet_state_dict.pth) for tests and benchmarks.
#include <filesystem>

#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

// Writes atomically (a temporary file renamed into place). Dtypes: those pth_reader.h reads.
void save_pth(const TensorMap& tensors, const std::filesystem::path& path);

}  // namespace u3d::nn
