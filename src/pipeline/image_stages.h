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

// Limits on the photo: smaller has too little of the object to draw four views from; larger is
// certainly not an object photo the networks can use (they see it at most at 2048 px).
inline constexpr int kMinPhotoSide = 64;
inline constexpr int kMaxPhotoSide = 8192;

// The photo, checked: an Error naming the file for what no stage can use (too small, too large, fully
// transparent), RGBA for the rest (grey replicated; no alpha is alpha 1, i.e. no background removed yet).
Image load_photo(const std::filesystem::path& path);

// photo: RGB(A) in [0, 1]. Returns the square RGBA front image the multi-view stage starts from. The
// background removal's mask is made solid (nn/pipelines/input_photo.h) unless raw_matte.
Image run_prepare_stage(const Image& photo, const NetworkOptions& network, bool raw_matte,
                        NetworkStageSummary& summary, NetworkCache* cache = nullptr);

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

// `unique3d upscale`: the image x4.
NetworkStageSummary upscale_image(const ImageRequest& request, ProgressListener* listener = nullptr);

// `unique3d matte`: the image with its background removed (RGBA) as the prepare stage removes it
// (nn::matte_photo: the mask made solid unless raw_matte, rembg's cut-out).
NetworkStageSummary remove_background(const ImageRequest& request, bool raw_matte,
                                      ProgressListener* listener = nullptr);

struct RefineRequest {
  std::filesystem::path views_dir;  // {front,right,back,left}_rgb.png, as `multiview` writes them
  std::filesystem::path front;      // the photo, prepared into the front image the IP-Adapter sees
  std::filesystem::path output_dir;
  NetworkOptions network;
  RefineOptions options;
  bool prepared_front = false;  // `front` is the prepare stage's output (generate's front.png): used as it is
  bool raw_matte = false;       // as run_prepare_stage
};

// `unique3d refine`: the four views refined, with the front photo prepared as `generate` prepares it
// (not when prepared_front), written only after the stage succeeded.
NetworkStageSummary refine_views(const RefineRequest& request, ProgressListener* listener = nullptr);

}  // namespace u3d
