#pragma once
// The facade's multi-view stage (`unique3d multiview`, and a stage of `generate`): the front image, the
// object on a transparent background, in; the multi-view model's four 256 px views out, drawn as the
// official app draws them (run_mvprediction: the image composited over white, 30 steps, guidance 1.5).
// The model is loaded when the stage starts and freed when it ends, or kept in a NetworkCache.
#include <array>
#include <filesystem>

#include "core/image.h"
#include "core/progress.h"
#include "pipeline/image_stages.h"
#include "pipeline/network_cache.h"
#include "pipeline/network_stage.h"

namespace u3d {

struct MultiViewOptions {
  int size = 256;  // side of the views; the model was trained at 256
  int steps = 30;
  double guidance_scale = 1.5;
};

// front: RGB(A) in [0, 1]. Returns the four views, RGB, in View order (front, right, back, left). With
// `cache` the model comes from it and stays there (pipeline/network_cache.h).
std::array<Image, 4> run_multiview_stage(const Image& front, const NetworkOptions& network,
                                         const MultiViewOptions& options, NetworkStageSummary& summary,
                                         NetworkCache* cache = nullptr);

struct MultiViewRequest {
  std::filesystem::path image;       // the photo, or the prepared front image when `prepared`
  std::filesystem::path output_dir;  // receives {front,right,back,left}_rgb.png
  NetworkOptions network;
  MultiViewOptions options;
  bool prepared = false;   // the image is the prepare stage's output (generate's front.png): used as it is
  bool raw_matte = false;  // as run_prepare_stage (pipeline/image_stages.h)
};

// Checks the request and the image before loading any weights (Error naming the file or value), prepares
// the photo as `generate` does (run_prepare_stage; not when `prepared`), runs the stage and writes the
// four views only after it succeeded (a new folder appears whole or not at all). So the views of a photo
// are those of `generate` with the same seed and options.
NetworkStageSummary generate_views(const MultiViewRequest& request, ProgressListener* listener = nullptr);

}  // namespace u3d
