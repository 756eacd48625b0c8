#pragma once
// Loads a weights file of either format, recognised by its content rather than its extension (diffusers
// names torch zip files *.bin, Unique3D names them *.pth): a zip archive is a torch.save checkpoint
// (pth_reader.h), anything else must be safetensors (safetensors.h).
#include <filesystem>

#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

TensorMap load_weights(const std::filesystem::path& path);

}  // namespace u3d::nn
