#pragma once
// The facade's normal-map stage (`unique3d normals`, and a stage of `generate`): four views in, a view
// set out (core/view_set.h), ready for ISOMER. As the official geo_reconstruct and predict_normals do:
// each view composited over white and resized to 512 px (Lanczos), one normal map per view from the
// image2normal model (30 steps, guidance 1.5), super-resolved x4 (Real-ESRGAN), the background keyed out
// by its colour (a pixel whose
// colour differs from the corner pixel (0,0) by at most 80 in the sum of its three 8-bit channels is
// background), and each map rotated from its view's camera space to world space. Masks: the front RGB
// image keeps its own alpha and lends it to the front normal map; the other views take their normal
// map's mask, eroded by one pixel. The model is loaded when the stage starts and freed when it ends, or
// kept in a NetworkCache (pipeline/network_cache.h).
#include <array>
#include <filesystem>
#include <optional>

#include "core/image.h"
#include "core/progress.h"
#include "pipeline/network_cache.h"
#include "pipeline/network_stage.h"

namespace u3d {

struct NormalOptions {
  int size = 512;  // side of the model's input and output; the model was trained at 512
  int steps = 30;
  double guidance_scale = 1.5;  // geo_reconstruct's value (predict_normals' own default is 2.0)
  bool upscale = true;          // Real-ESRGAN x4 on each map before its background is keyed out
};

struct ViewSetImages {
  std::array<Image, 4> rgb;      // RGBA, alpha = mask; all the size of the largest input view
  std::array<Image, 4> normals;  // RGBA, world-space (n + 1) / 2, background RGB 0
  // (both at the 256 levels of the 8-bit files that hold a view set: core/image.h, quantized_8bit)
};

// views: RGB(A) in [0, 1], in View order; the front view should carry the object's alpha (else its mask
// comes from its normal map too).
ViewSetImages run_normal_stage(const std::array<Image, 4>& views, const NetworkOptions& network,
                               const NormalOptions& options, NetworkStageSummary& summary,
                               NetworkCache* cache = nullptr);

struct NormalRequest {
  std::filesystem::path views_dir;             // {front,right,back,left}_rgb.png
  std::optional<std::filesystem::path> front;  // replaces front_rgb.png (the input photo, as generate uses)
  std::filesystem::path output_dir;            // receives the view set: _rgb.png and _normal.png per view
  NetworkOptions network;
  NormalOptions options;
  bool prepared_front = false;  // `front` is the prepare stage's output (generate's front.png): used as it is
  bool raw_matte = false;       // as run_prepare_stage (pipeline/image_stages.h)
};

// Checks the request and every image before loading any weights, prepares `front` as `generate` does
// (run_prepare_stage, pipeline/image_stages.h; not when prepared_front), runs the stage and writes the
// view set only after it succeeded (a new folder appears whole or not at all).
NetworkStageSummary predict_view_normals(const NormalRequest& request, ProgressListener* listener = nullptr);

}  // namespace u3d
