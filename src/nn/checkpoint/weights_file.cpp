#include "nn/checkpoint/weights_file.h"

#include <fstream>

#include "core/error.h"
#include "nn/checkpoint/pth_reader.h"
#include "nn/checkpoint/safetensors.h"

namespace u3d::nn {

TensorMap load_weights(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  require(bool(in), "cannot open weights file " + path.string());
  char magic[2] = {};
  in.read(magic, 2);
  if (in.gcount() == 2 && magic[0] == 'P' && magic[1] == 'K') return load_pth(path);
  return load_safetensors(path);
}

}  // namespace u3d::nn
