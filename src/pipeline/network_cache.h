#pragma once
// The networks of generate's stages kept loaded from one run to the next, for callers that run many photos
// with one model folder (`unique3d batch`, docs/cluster.md): a stage given a cache takes its networks
// from it, which loads each on its first use and keeps it, so that a shard of photos reads each
// checkpoint once. Only while memory allows: before a network is loaded, when the memory left to the
// process (core/memory.h, available_memory_mib) is less than the network's estimate plus
// kStageWorkMiB for the stage's work, the networks kept so far are freed first, and the stage runs as
// without a cache (each stage loads its networks when it starts and frees them when it ends). The
// estimate is the size of the network's files, doubled when it runs in fp32 (the files may hold half
// precision).
#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "nn/precision_kind.h"
#include "pipeline/model_folder.h"

namespace u3d {

namespace nn {
class UpscaleModel;
class MattingModel;
class MultiViewModel;
class RefineEncoders;
class RefineModel;
class NormalModel;
}  // namespace nn

// Room kept for a stage's activations beside its networks: the normal stage in fp32 peaks about 3 GB
// above its weights (README, "Speed": 8,096 MiB with 5 GB of networks).
inline constexpr double kStageWorkMiB = 4096.0;

class NetworkCache {
 public:
  // Each network of `folder` in `precision`; a call with another folder or precision frees the kept
  // ones first. The normal model comes with its UNets loaded.
  std::shared_ptr<nn::UpscaleModel> upscaler(const ModelFolder& folder, nn::Precision precision);
  std::shared_ptr<nn::MattingModel> matting(const ModelFolder& folder, nn::Precision precision);
  std::shared_ptr<nn::MultiViewModel> multiview(const ModelFolder& folder, nn::Precision precision);
  std::shared_ptr<nn::RefineEncoders> refine_encoders(const ModelFolder& folder, nn::Precision precision);
  std::shared_ptr<nn::RefineModel> refine_model(const ModelFolder& folder, nn::Precision precision);
  std::shared_ptr<nn::NormalModel> normals(const ModelFolder& folder, nn::Precision precision);

  // How many networks were read from their files so far, and how many times the kept ones were freed
  // for lack of memory.
  size_t loads() const { return loads_; }
  size_t evictions() const { return evictions_; }
  void clear() { models_.clear(); }

 private:
  std::shared_ptr<void> get(const std::string& name, const ModelFolder& folder, nn::Precision precision,
                            const std::vector<std::filesystem::path>& files,
                            const std::function<std::shared_ptr<void>()>& load);

  std::map<std::string, std::shared_ptr<void>> models_;
  std::filesystem::path root_;
  nn::Precision precision_ = nn::Precision::kFp32;
  size_t loads_ = 0;
  size_t evictions_ = 0;
};

}  // namespace u3d
