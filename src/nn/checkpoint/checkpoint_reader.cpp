#include "nn/checkpoint/checkpoint_reader.h"

#include "core/memory.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/pth_reader.h"
#include "nn/checkpoint/safetensors.h"

namespace u3d::nn {

torch::TensorOptions CheckpointReader::options() const {
  return checking() ? torch::TensorOptions().device(torch::kMeta) : torch::TensorOptions();
}

TensorMap CheckpointReader::read(const std::filesystem::path& file) const {
  if (!checking()) return load_weights_file(file);
  return file.extension() == ".safetensors" ? inspect_safetensors(file) : inspect_pth(file);
}

LoadReport CheckpointReader::apply(torch::nn::Module& module, TensorMap weights, const LoadPolicy& policy,
                                   const std::string& source) const {
  if (checking()) return check_state_dict(module, weights, policy, source);
  LoadReport report = load_state_dict(module, std::move(weights), policy, source);
  release_freed_memory();  // the file's tensors, freed as they were copied
  return report;
}

LoadReport CheckpointReader::load(torch::nn::Module& module, const std::filesystem::path& file,
                                  const LoadPolicy& policy) const {
  return apply(module, read(file), policy, file.string());
}

}  // namespace u3d::nn
