#include "pipeline/network_cache.h"

#include <system_error>

#include "core/memory.h"
#include "core/progress.h"
#include "nn/pipelines/matting.h"
#include "nn/pipelines/unique3d_multiview.h"
#include "nn/pipelines/unique3d_normal.h"
#include "nn/pipelines/unique3d_refine.h"
#include "nn/pipelines/upscale.h"
#include "pipeline/model_check.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

double files_mib(const std::vector<fs::path>& files) {
  double bytes = 0.0;
  for (const fs::path& f : files) {
    std::error_code ec;
    const auto size = fs::file_size(f, ec);
    if (!ec) bytes += double(size);
  }
  return bytes / (1024.0 * 1024.0);
}

}  // namespace

std::shared_ptr<void> NetworkCache::get(const std::string& name, const ModelFolder& folder, nn::Precision precision,
                                        const std::vector<fs::path>& files,
                                        const std::function<std::shared_ptr<void>()>& load) {
  if (folder.root() != root_ || precision != precision_) {
    models_.clear();
    root_ = folder.root();
    precision_ = precision;
  }
  if (auto it = models_.find(name); it != models_.end()) return it->second;
  const double need = files_mib(files) * (precision == nn::Precision::kFp32 ? 2.0 : 1.0) + kStageWorkMiB;
  if (!models_.empty() && available_memory_mib() < need) {
    models_.clear();
    release_freed_memory();
    ++evictions_;
    progress("freeing the networks kept so far: " + name + " needs about " + std::to_string(int(need)) +
             " MiB with its work, more than is left");
  }
  std::shared_ptr<void> model = load();
  ++loads_;
  models_[name] = model;
  return model;
}

std::shared_ptr<nn::UpscaleModel> NetworkCache::upscaler(const ModelFolder& folder, nn::Precision precision) {
  const fs::path file = folder.upscaler();
  return std::static_pointer_cast<nn::UpscaleModel>(get("upscaler", folder, precision, {file}, [&] {
    return std::shared_ptr<void>(nn::UpscaleModel::load(file, precision));
  }));
}

std::shared_ptr<nn::MattingModel> NetworkCache::matting(const ModelFolder& folder, nn::Precision precision) {
  const fs::path file = folder.matting();
  return std::static_pointer_cast<nn::MattingModel>(get("matting", folder, precision, {file}, [&] {
    return std::shared_ptr<void>(nn::MattingModel::load(file, precision));
  }));
}

std::shared_ptr<nn::MultiViewModel> NetworkCache::multiview(const ModelFolder& folder, nn::Precision precision) {
  return std::static_pointer_cast<nn::MultiViewModel>(
      get("multi-view model", folder, precision, nn::MultiViewModel::files(folder.img2mvimg()),
          [&] { return std::shared_ptr<void>(nn::MultiViewModel::load(folder.img2mvimg(), precision)); }));
}

// Both refinement halves are estimated by the files of both (nn/pipelines/unique3d_refine.h lists them
// together).
std::shared_ptr<nn::RefineEncoders> NetworkCache::refine_encoders(const ModelFolder& folder, nn::Precision precision) {
  return std::static_pointer_cast<nn::RefineEncoders>(
      get("refinement encoders", folder, precision, nn::RefineModel::files(refine_checkpoints(folder)),
          [&] { return std::shared_ptr<void>(nn::RefineEncoders::load(refine_checkpoints(folder), precision)); }));
}

std::shared_ptr<nn::RefineModel> NetworkCache::refine_model(const ModelFolder& folder, nn::Precision precision) {
  return std::static_pointer_cast<nn::RefineModel>(
      get("refinement model", folder, precision, nn::RefineModel::files(refine_checkpoints(folder)),
          [&] { return std::shared_ptr<void>(nn::RefineModel::load(refine_checkpoints(folder), precision)); }));
}

std::shared_ptr<nn::NormalModel> NetworkCache::normals(const ModelFolder& folder, nn::Precision precision) {
  const fs::path variations = folder.image_variations_for_normals(), image2normal = folder.image2normal();
  return std::static_pointer_cast<nn::NormalModel>(
      get("normal model", folder, precision, nn::NormalModel::files(variations, image2normal),
          [&] { return std::shared_ptr<void>(nn::NormalModel::load(variations, image2normal, precision)); }));
}

}  // namespace u3d
