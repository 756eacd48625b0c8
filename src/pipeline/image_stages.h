#pragma once
// The facade's image stages around the diffusion models, as the official app runs them: preparing the
// photo (x4 super-resolution when at most 512 px wide, background removal when it has no transparency,
// colours on white, crop to the object and square; nn/pipelines/input_photo.h), the ControlNet-tile +
// IP-Adapter refinement of the four views (nn/pipelines/unique3d_refine.h), Real-ESRGAN x4
// (nn/pipelines/upscale.h) and background removal (nn/pipelines/matting.h); each loads its networks
// when it starts and frees them when it ends, or takes them from a NetworkCache that keeps them
// (pipeline/network_cache.h). Plus the requests of the `upscale`, `matte` and `refine`
// commands.
#include <array>
#include <filesystem>
#include <optional>
#include <vector>

#include "core/image.h"
#include "core/progress.h"
#include "pipeline/network_cache.h"
#include "pipeline/network_stage.h"

namespace u3d {

// photo: RGB(A) in [0, 1]. Returns the square RGBA front image the multi-view stage starts from.
Image run_prepare_stage(const Image& photo, const NetworkOptions& network, NetworkStageSummary& summary,
                        NetworkCache* cache = nullptr);

struct RefineOptions {
  int size = 1024;        // side of the 2x2 grid the pass redraws; each view comes back at size / 2
  int steps = 50;         // the schedule's steps, of which the last int(steps * strength) run
  double strength = 0.2;  // how much of the schedule runs: 0.2 redraws fine detail only
};

// views: the multi-view stage's four views in View order (one size); front: the prepared photo. Returns
// the four refined views (RGB, options.size / 2 px).
std::array<Image, 4> run_refine_stage(const std::array<Image, 4>& views, const Image& front,
                                      const NetworkOptions& network, const RefineOptions& options,
                                      NetworkStageSummary& summary, NetworkCache* cache = nullptr);

// Each image x4 (RGB or RGBA; alpha is upscaled too), one load of the upscaler for all.
std::vector<Image> run_upscale_stage(const std::vector<Image>& images, const NetworkOptions& network,
                                     NetworkStageSummary& summary, NetworkCache* cache = nullptr);

struct ImageRequest {
  std::filesystem::path image;
  std::filesystem::path output;  // .png (.jpg drops the alpha)
  NetworkOptions network;
};

// `unique3d upscale`: the image x4. `unique3d matte`: the image with its background removed (RGBA).
NetworkStageSummary upscale_image(const ImageRequest& request, ProgressListener* listener = nullptr);
NetworkStageSummary remove_background(const ImageRequest& request, ProgressListener* listener = nullptr);

struct RefineRequest {
  std::filesystem::path views_dir;  // {front,right,back,left}_rgb.png, as `multiview` writes them
  std::filesystem::path front;      // the object photo (transparent background) the IP-Adapter sees
  std::filesystem::path output_dir;
  NetworkOptions network;
  RefineOptions options;
};

// `unique3d refine`: the four views refined, written only after the stage succeeded.
NetworkStageSummary refine_views(const RefineRequest& request, ProgressListener* listener = nullptr);

}  // namespace u3d
