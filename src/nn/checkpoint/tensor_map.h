#pragma once
// A state dict: tensor name (the Python library's key, e.g. "down_blocks.0.resnets.0.conv1.weight")
// to tensor. Ordered so reports and iteration are deterministic.
#include <torch/torch.h>

#include <map>
#include <string>

namespace u3d::nn {

using TensorMap = std::map<std::string, torch::Tensor>;

}  // namespace u3d::nn
