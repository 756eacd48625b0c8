#include "pipeline/image_stages.h"

#include <algorithm>
#include <cctype>
#include <optional>

#include "core/atomic_file.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/view_set.h"
#include "nn/pipelines/input_photo.h"
#include "nn/pipelines/matting.h"
#include "nn/pipelines/unique3d_refine.h"
#include "nn/pipelines/upscale.h"
#include "pipeline/model_check.h"
#include "pipeline/model_folder.h"
#include "pipeline/tensor_image.h"

namespace u3d {
namespace {

// An Error before any work when `output` cannot be an image file save_image writes.
void check_image_output(const std::filesystem::path& output) {
  std::string ext = output.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  require(ext == ".png" || ext == ".jpg" || ext == ".jpeg",
          "output " + output.string() + ": unsupported extension (use .png, or .jpg without alpha)");
  const std::filesystem::path dir = output.parent_path().empty() ? "." : output.parent_path();
  require(std::filesystem::is_directory(dir), "output folder " + dir.string() + " does not exist");
}

}  // namespace

Image load_photo(const std::filesystem::path& path) {
  const Image photo = load_image_rgba(path);
  const std::string name = "photo " + path.string();
  const std::string size = std::to_string(photo.width) + "x" + std::to_string(photo.height);
  require(std::min(photo.width, photo.height) >= kMinPhotoSide,
          name + " is " + size + ": too small to reconstruct from (at least " + std::to_string(kMinPhotoSide) +
              " px per side)");
  require(std::max(photo.width, photo.height) <= kMaxPhotoSide,
          name + " is " + size + ": larger than " + std::to_string(kMaxPhotoSide) + " px per side; scale it down first");
  bool visible = false;
  for (size_t i = 0; i < photo.pixel_count() && !visible; ++i) visible = photo.data[4 * i + 3] > 0.f;
  require(visible, name + " is fully transparent: nothing to reconstruct");
  return photo;
}

Image run_prepare_stage(const Image& photo, const NetworkOptions& network, bool raw_matte,
                        NetworkStageSummary& summary, NetworkCache* cache) {
  const ModelFolder folder(network.models);
  summary.precision = resolve_precision(network);
  StageTimer timer("preparing the photo");
  const nn::InputPhotoModels models{
      [&]() -> std::shared_ptr<nn::UpscaleModel> {
        if (cache) return cache->upscaler(folder, summary.precision);
        return nn::UpscaleModel::load(folder.upscaler(), summary.precision);
      },
      [&]() -> std::shared_ptr<nn::MattingModel> {
        if (cache) return cache->matting(folder, summary.precision);
        return nn::MattingModel::load(folder.matting(), summary.precision);
      }};
  const Image front = tensor_to_image(nn::prepare_input_photo(image_to_uint8(photo), models, false, raw_matte));
  summary.timings.push_back({"prepare", timer.finish()});
  summary.peak_memory_mib = peak_memory_mib();
  return front;
}

std::array<Image, 4> run_refine_stage(const std::array<Image, 4>& views, const Image& front,
                                      const NetworkOptions& network, const RefineOptions& options,
                                      NetworkStageSummary& summary, NetworkCache* cache) {
  const ModelFolder folder(network.models);
  summary.precision = resolve_precision(network);
  nn::RefineSettings settings;
  settings.size = options.size;
  settings.steps = options.steps;
  settings.strength = options.strength;
  settings.free_networks_as_done = !cache;
  // The encoders run once and are freed before the denoising models load (nn/pipelines/unique3d_refine.h).
  StageTimer encode_timer("encoding the prompt, the front view and the views");
  std::vector<torch::Tensor> inputs;
  for (const Image& view : views) inputs.push_back(image_to_uint8(composite_over_white(view)));
  std::shared_ptr<nn::RefineEncoders> encoders = cache ? cache->refine_encoders(folder, summary.precision)
                                                       : nn::RefineEncoders::load(refine_checkpoints(folder), summary.precision);
  nn::RefineConditioning conditioning = encoders->encode(inputs, image_to_uint8(composite_over_white(front)), settings);
  encoders.reset();
  release_freed_memory();  // the encoders
  summary.timings.push_back({"refinement encoders", encode_timer.finish()});

  StageTimer load_timer("loading the refinement models");
  std::shared_ptr<nn::RefineModel> model = cache ? cache->refine_model(folder, summary.precision)
                                                 : nn::RefineModel::load(refine_checkpoints(folder), summary.precision);
  summary.timings.push_back({"load refinement models", load_timer.finish()});

  StageTimer timer("refining the views");
  nn::SeededNoise noise(network.seed);
  const torch::Tensor refined = model->run(conditioning, settings, noise);
  model.reset();
  release_freed_memory();
  summary.timings.push_back({"refine", timer.finish()});
  summary.peak_memory_mib = peak_memory_mib();
  std::array<Image, 4> out;
  for (View v : kAllViews) out[size_t(v)] = tensor_to_image(refined[int(v)]);
  return out;
}

std::vector<Image> run_upscale_stage(const std::vector<Image>& images, const NetworkOptions& network,
                                     NetworkStageSummary& summary, NetworkCache* cache) {
  const ModelFolder folder(network.models);
  summary.precision = resolve_precision(network);
  StageTimer load_timer("loading the upscaler");
  std::shared_ptr<nn::UpscaleModel> model = cache ? cache->upscaler(folder, summary.precision)
                                                  : nn::UpscaleModel::load(folder.upscaler(), summary.precision);
  summary.timings.push_back({"load upscaler", load_timer.finish()});
  StageTimer timer("upscaling x4");
  std::vector<torch::Tensor> inputs;
  for (const Image& image : images) inputs.push_back(image_to_uint8(image));
  std::vector<Image> out;
  for (const torch::Tensor& upscaled : model->upscale(inputs)) out.push_back(tensor_to_image(upscaled));
  summary.timings.push_back({"upscale", timer.finish()});
  summary.peak_memory_mib = peak_memory_mib();
  return out;
}

NetworkStageSummary upscale_image(const ImageRequest& request, ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  check_image_output(request.output);
  const Image image = load_image(request.image);
  NetworkStageSummary summary;
  const Image out = run_upscale_stage({image}, request.network, summary).front();
  save_image(out, request.output);
  summary.written.push_back(request.output);
  return summary;
}

NetworkStageSummary remove_background(const ImageRequest& request, bool raw_matte, ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  check_image_output(request.output);
  const Image image = load_image(request.image);
  const ModelFolder folder(request.network.models);
  NetworkStageSummary summary;
  summary.precision = resolve_precision(request.network);
  StageTimer load_timer("loading the background-removal model");
  auto model = nn::MattingModel::load(folder.matting(), summary.precision);
  summary.timings.push_back({"load matting model", load_timer.finish()});
  StageTimer timer("removing the background");
  const Image out = tensor_to_image(nn::matte_photo(image_to_uint8(image), *model, raw_matte));
  model.reset();
  summary.timings.push_back({"matte", timer.finish()});
  summary.peak_memory_mib = peak_memory_mib();
  save_image(out, request.output);
  summary.written.push_back(request.output);
  return summary;
}

NetworkStageSummary refine_views(const RefineRequest& request, ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  require(request.options.steps >= 1, "refinement steps must be at least 1");
  std::array<Image, 4> views;
  for (View v : kAllViews) views[size_t(v)] = load_image(request.views_dir / view_file_name(v, false));
  NetworkStageSummary summary;
  const Image front = request.prepared_front
                          ? load_image(request.front)
                          : run_prepare_stage(load_photo(request.front), request.network, request.raw_matte, summary);
  const std::array<Image, 4> refined = run_refine_stage(views, front, request.network, request.options, summary);
  write_folder_atomically(request.output_dir, [&](const std::filesystem::path& folder) {
    for (View v : kAllViews) save_image(refined[size_t(v)], folder / view_file_name(v, false));
  });
  for (View v : kAllViews) summary.written.push_back(request.output_dir / view_file_name(v, false));
  return summary;
}

}  // namespace u3d
