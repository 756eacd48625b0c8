#pragma once
// How a model's loader reads its checkpoints: for real, or to check them. Loading reads every tensor into
// a model built on the CPU. Checking reads only each file's names, dtypes and shapes (inspect_safetensors,
// inspect_pth: headers and zip directories, so a truncated download fails) into a model built on the
// meta device, where nothing is allocated: the checkpoints of a whole Unique3D stage are checked in about
// a second. Every loader runs the same code in both modes, so a check that passes means loading passes
// the same key, shape and dtype checks (state_dict_loader.h); only what needs the data (zip CRCs) is left
// to loading.
#include <filesystem>
#include <string>

#include "nn/checkpoint/state_dict_loader.h"
#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

class CheckpointReader {
 public:
  enum class Mode { kLoad, kCheck };
  CheckpointReader() = default;
  explicit CheckpointReader(Mode mode) : mode_(mode) {}

  bool checking() const { return mode_ == Mode::kCheck; }
  // Where the loader builds its models: the CPU, or the meta device when checking.
  torch::TensorOptions options() const;
  // The file's tensors (safetensors by extension, else torch zip), or meta tensors of their shapes.
  TensorMap read(const std::filesystem::path& file) const;
  // load_state_dict (which frees a map moved in as it copies), or check_state_dict when checking.
  LoadReport apply(torch::nn::Module& module, TensorMap weights, const LoadPolicy& policy,
                   const std::string& source) const;
  // read() then apply().
  LoadReport load(torch::nn::Module& module, const std::filesystem::path& file, const LoadPolicy& policy = {}) const;

 private:
  Mode mode_ = Mode::kLoad;
};

}  // namespace u3d::nn
