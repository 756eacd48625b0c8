#include "pipeline/generate.h"

#include <algorithm>
#include <optional>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/view_set.h"
#include "nn/pipelines/input_photo.h"
#include "nn/preprocess/pil_resize.h"
#include "pipeline/image_stages.h"
#include "pipeline/model_check.h"
#include "pipeline/model_folder.h"
#include "pipeline/tensor_image.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

enum Stage { kPrepare, kMultiView, kRefine, kUpscale, kNormals, kReconstruct, kStageCount };

constexpr int kSuperResolveMaxWidth = int(nn::kSuperResolveMaxWidth);

// Where a stage's outputs live inside the intermediates folder.
fs::path stage_folder(Stage stage) {
  switch (stage) {
    case kMultiView: return "multiview";
    case kRefine: return "refined";
    case kUpscale: return "upscaled";
    case kNormals: return "views";
    default: return {};
  }
}

std::vector<fs::path> stage_files(Stage stage) {
  if (stage == kPrepare) return {"front.png"};
  std::vector<fs::path> files;
  for (View v : kAllViews) {
    files.push_back(stage_folder(stage) / view_file_name(v, false));
    if (stage == kNormals) files.push_back(stage_folder(stage) / view_file_name(v, true));
  }
  return files;
}

bool stage_complete(const fs::path& dir, Stage stage) {
  const std::vector<fs::path> files = stage_files(stage);
  return std::all_of(files.begin(), files.end(), [&](const fs::path& f) { return fs::is_regular_file(dir / f); });
}

Image to_rgba(const Image& image) {
  if (image.channels == 4) return image;
  Image out(image.width, image.height, 4, 1.f);
  for (size_t i = 0; i < image.pixel_count(); ++i) {
    const float* p = image.data.data() + i * image.channels;
    const bool gray = image.channels < 3;
    for (int c = 0; c < 3; ++c) out.data[4 * i + c] = p[gray ? 0 : c];
    if (image.channels == 2) out.data[4 * i + 3] = p[1];
  }
  return out;
}

bool opaque(const Image& rgba) {
  for (size_t i = 0; i < rgba.pixel_count(); ++i)
    if (rgba.data[4 * i + 3] < 1.f) return false;
  return true;
}

Image lanczos_resize(const Image& rgb, int size) {
  return tensor_to_image(nn::pil_resize(nn::image_to_uint8_rgb(rgb), size, size, nn::PilFilter::Lanczos));
}

std::array<std::string, 4> view_names(bool normal) {
  std::array<std::string, 4> names;
  for (View v : kAllViews) names[size_t(v)] = view_file_name(v, normal);
  return names;
}

// One run of the stages: what they hand each other, and the report.
struct Run {
  Run(const GenerateRequest& r, NetworkCache* c) : request(r), cache(c) {}

  const GenerateRequest& request;
  NetworkCache* cache;
  GenerateSummary summary;
  Image front;                 // prepare's output, the front view of the view set
  std::array<Image, 4> views;  // multiview's, refine's, upscale's outputs in turn
  std::optional<ViewSet> view_set;
  std::optional<MemoryPeakWatch> stage_memory;  // the running stage's peak memory

  // Writes a stage's images into the intermediates folder when one is kept.
  void keep(const std::vector<std::pair<fs::path, const Image*>>& images) {
    if (request.keep_intermediates.empty()) return;
    for (const auto& [relative, image] : images) {
      const fs::path path = request.keep_intermediates / relative;
      ensure_directory(path.parent_path());
      save_image(*image, path);
      summary.written.push_back(path);
    }
  }
  void keep_views(Stage stage) {
    std::vector<std::pair<fs::path, const Image*>> images;
    for (View v : kAllViews) images.push_back({stage_folder(stage) / view_file_name(v, false), &views[size_t(v)]});
    keep(images);
  }
  void report(Stage stage, double seconds, bool resumed) {
    summary.stages.push_back({generate_stage_names()[stage], seconds, resumed ? 0.0 : stage_memory->peak_mib(), resumed});
  }

  // Reads what `stage` handed on from the intermediates folder.
  void resume(Stage stage) {
    const fs::path& dir = request.from_intermediates;
    if (stage == kPrepare) front = to_rgba(load_image(dir / "front.png"));
    if (stage == kMultiView || stage == kRefine || stage == kUpscale)
      for (View v : kAllViews) views[size_t(v)] = load_image(dir / stage_folder(stage) / view_file_name(v, false));
    // The upscale stage's front view is the prepared photo, super-resolved when it was small.
    if (stage == kUpscale) front = to_rgba(views[size_t(View::Front)]);
    if (stage == kNormals)
      view_set = load_view_set(dir / stage_folder(kNormals), NormalSpace::World, NormalCheck::kPredicted);
  }

  // `photo` is given up once the prepare stage has made the front view of it.
  void run(Stage stage, std::optional<Image>& photo) {
    switch (stage) {
      case kPrepare: {
        NetworkStageSummary st;
        front = run_prepare_stage(*photo, request.network, request.raw_matte, st, cache);
        photo.reset();
        keep({{"front.png", &front}});
        report(stage, st.total_seconds(), false);
        break;
      }
      case kMultiView: {
        NetworkStageSummary s;
        views = run_multiview_stage(front, request.network, request.multiview, s, cache);
        keep_views(stage);
        report(stage, s.total_seconds(), false);
        break;
      }
      case kRefine: {
        if (request.refine) {
          NetworkStageSummary st;
          views = run_refine_stage(views, front, request.network, request.refine_options, st, cache);
          report(stage, st.total_seconds(), false);
        } else {
          // The size the refinement would give them (512 px at the official grid of 1024).
          const int size = request.refine_options.size / 2;
          StageTimer timer("resizing the views to " + std::to_string(size) + " px");
          for (Image& view : views) view = lanczos_resize(view, size);
          report(stage, timer.finish(), false);
        }
        keep_views(stage);
        break;
      }
      case kUpscale: {
        // The side views x4; the front view is the prepared photo, x4 when at most 512 px wide.
        NetworkStageSummary st;
        std::vector<Image> inputs(views.begin() + 1, views.end());
        const bool small_front = front.width <= kSuperResolveMaxWidth;
        if (small_front) inputs.push_back(front);
        std::vector<Image> upscaled = run_upscale_stage(inputs, request.network, st, cache);
        for (size_t i = 1; i < 4; ++i) views[i] = std::move(upscaled[i - 1]);
        if (small_front) front = std::move(upscaled[3]);
        views[size_t(View::Front)] = front;
        keep_views(stage);
        report(stage, st.total_seconds(), false);
        break;
      }
      case kNormals: {
        // The front view is the prepared photo, as in the official geo_reconstruct. The view set made below
        // replaces the views and the photo, so they move into the stage rather than staying beside a copy
        // (at 2048 px, 256 MiB held through the normal model's run).
        NetworkStageSummary s;
        std::array<Image, 4> inputs = std::move(views);
        inputs[size_t(View::Front)] = std::move(front);
        const ViewSetImages set = run_normal_stage(inputs, request.network, request.normals, s, cache);
        std::vector<std::pair<fs::path, const Image*>> images;
        for (View v : kAllViews) {
          images.push_back({stage_folder(stage) / view_file_name(v, false), &set.rgb[size_t(v)]});
          images.push_back({stage_folder(stage) / view_file_name(v, true), &set.normals[size_t(v)]});
        }
        keep(images);
        report(stage, s.total_seconds(), false);
        view_set = make_view_set(set.rgb, set.normals, NormalSpace::World, view_names(false), view_names(true),
                                 NormalCheck::kPredicted);
        break;
      }
      case kReconstruct: {
        ReconstructRequest r;
        r.output = request.output;
        r.previews = request.previews;
        r.options = request.reconstruct;
        r.official_output_scale = request.official_output_scale;
        r.texture_format = request.texture_format;
        summary.reconstruction = reconstruct_view_set(*view_set, r);
        report(stage, summary.reconstruction.total_seconds(), false);
        summary.written.insert(summary.written.end(), summary.reconstruction.written.begin(),
                               summary.reconstruction.written.end());
        break;
      }
      case kStageCount: break;
    }
  }
};

}  // namespace

double GenerateSummary::total_seconds() const {
  double total = 0.0;
  for (const GenerateStageReport& s : stages) total += s.seconds;
  return total;
}

const std::vector<std::string>& generate_stage_names() {
  static const std::vector<std::string> names = {"prepare", "multiview", "refine", "upscale", "normals", "reconstruct"};
  return names;
}

GenerateSummary generate(const GenerateRequest& request, ProgressListener* listener, NetworkCache* cache) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  if (!request.output.empty()) check_mesh_output(request.output);
  require(request.multiview.steps >= 1 && request.normals.steps >= 1, "denoising steps must be at least 1");

  // Where to start: after the last stage whose outputs are all in from_intermediates.
  Stage start = kPrepare;
  if (!request.from_intermediates.empty()) {
    require(fs::is_directory(request.from_intermediates),
            "intermediates folder " + request.from_intermediates.string() + " does not exist");
    for (int s = kNormals; s >= kPrepare; --s)
      if (stage_complete(request.from_intermediates, Stage(s))) {
        start = Stage(s + 1);
        break;
      }
    require(start != kPrepare && stage_complete(request.from_intermediates, kPrepare),
            "intermediates folder " + request.from_intermediates.string() +
                " holds no run to resume: it needs front.png and the outputs of a later stage (multiview/, refined/, "
                "upscaled/ or views/)");
    std::string done;
    for (int s = kPrepare; s < start; ++s) done += (s == kPrepare ? "" : s + 1 == start ? " and " : ", ") + generate_stage_names()[s];
    progress("resuming from " + request.from_intermediates.string() + ", where " + done +
             (start == kPrepare + 1 ? " is" : " are") + " done" +
             (request.image.empty() ? "" : "; its front.png is the photo (" + request.image.string() + " is not read)"));
  } else {
    require(!request.image.empty(), "no photo given (or resume a run with --from-intermediates)");
  }
  if (!request.keep_intermediates.empty()) ensure_directory(request.keep_intermediates);

  // Everything the stages to run need is checked before the first of them starts.
  std::optional<Image> photo;
  if (start == kPrepare) {
    photo = load_photo(request.image);
  }
  // Their files are there and match the networks (a truncated or wrong checkpoint fails here, not after
  // minutes of denoising); the photo needs the upscaler when it is small, the views always do.
  std::vector<Network> networks;
  if (start <= kPrepare && opaque(*photo)) networks.push_back(Network::kMatting);
  if (start <= kNormals) networks.push_back(Network::kUpscaler);
  if (start <= kMultiView) networks.push_back(Network::kMultiView);
  if (start <= kRefine && request.refine) networks.push_back(Network::kRefine);
  if (start <= kNormals) networks.push_back(Network::kNormals);
  require_networks(ModelFolder(request.network.models), networks);

  Run run(request, cache);
  run.summary.precision = resolve_precision(request.network);
  for (int s = kPrepare; s < kStageCount; ++s) {
    if (s >= start) {
      release_freed_memory();     // what the stage before left in the heap
      run.stage_memory.emplace();  // each stage reports its own peak
      run.run(Stage(s), photo);
    } else {
      // The front image is needed to the end; the views only from the stage before the first to run.
      if (s == kPrepare || s == start - 1) run.resume(Stage(s));
      run.report(Stage(s), 0.0, true);
    }
  }
  run.stage_memory.reset();
  run.summary.peak_memory_mib = peak_memory_mib();
  return run.summary;
}

}  // namespace u3d
