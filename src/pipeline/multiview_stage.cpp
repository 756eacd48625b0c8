#include "pipeline/multiview_stage.h"

#include <optional>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/view_set.h"
#include "nn/pipelines/unique3d_multiview.h"
#include "nn/preprocess/pil_resize.h"
#include "pipeline/model_check.h"
#include "pipeline/model_folder.h"
#include "pipeline/tensor_image.h"

namespace u3d {
std::array<Image, 4> run_multiview_stage(const Image& front, const NetworkOptions& network,
                                         const MultiViewOptions& options, NetworkStageSummary& summary,
                                         NetworkCache* cache) {
  const ModelFolder folder(network.models);
  summary.precision = resolve_precision(network);
  StageTimer load_timer("loading the multi-view model");
  std::shared_ptr<nn::MultiViewModel> model = cache ? cache->multiview(folder, summary.precision)
                                                    : nn::MultiViewModel::load(folder.img2mvimg(), summary.precision);
  summary.timings.push_back({"load multi-view model", load_timer.finish()});

  StageTimer timer("multi-view generation");
  nn::MultiViewSettings settings;
  settings.size = options.size;
  settings.steps = options.steps;
  settings.guidance_scale = options.guidance_scale;
  settings.free_networks_as_done = !cache;
  nn::SeededNoise noise(network.seed);
  const torch::Tensor views = model->run(nn::image_to_uint8_rgb(composite_over_white(front)), settings, noise);
  model.reset();
  release_freed_memory();
  summary.timings.push_back({"multi-view", timer.finish()});
  summary.peak_memory_mib = peak_memory_mib();
  std::array<Image, 4> out;
  for (View v : kAllViews) out[size_t(v)] = tensor_to_image(views[int(v)]);
  return out;
}

NetworkStageSummary generate_views(const MultiViewRequest& request, ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  require(request.options.steps >= 1, "multi-view steps must be at least 1");
  require(request.options.size >= 8 && request.options.size % 8 == 0, "multi-view size must be a multiple of 8");
  NetworkStageSummary summary;
  Image front;
  if (request.prepared) {
    front = load_image(request.image);
    const std::string advice = ": a prepared image has the object on a transparent background (RGBA PNG; "
                               "without --prepared the photo is prepared first)";
    require(front.channels == 4, "image " + request.image.string() + " has no alpha channel" + advice);
    bool transparent = false;
    for (size_t i = 0; i < front.pixel_count() && !transparent; ++i) transparent = front.data[4 * i + 3] < 1.f;
    require(transparent, "image " + request.image.string() + " is opaque everywhere" + advice);
  } else {
    const Image photo = load_photo(request.image);
    require_networks(ModelFolder(request.network.models), {Network::kMultiView});  // before the preparation runs
    front = run_prepare_stage(photo, request.network, request.raw_matte, summary);
  }
  const std::array<Image, 4> views = run_multiview_stage(front, request.network, request.options, summary);
  StageTimer write_timer("writing views");
  write_folder_atomically(request.output_dir, [&](const std::filesystem::path& folder) {
    for (View v : kAllViews) save_image(views[size_t(v)], folder / view_file_name(v, /*normal=*/false));
  });
  for (View v : kAllViews) summary.written.push_back(request.output_dir / view_file_name(v, false));
  summary.timings.push_back({"write", write_timer.finish()});
  return summary;
}

}  // namespace u3d
