// `unique3d upscale`, `unique3d matte` and `unique3d refine`: the image stages around the diffusion
// models, one command each (pipeline/image_stages.h).
#include "cli/command.h"
#include "cli/network_options.h"
#include "pipeline/image_stages.h"

namespace u3d::cli {
namespace {

struct ImageArgs {
  ImageRequest request;
  NetworkArgs network;
  bool raw_matte = false;
};

std::shared_ptr<ImageArgs> add_image_options(CLI::App& sub, const char* output_help) {
  auto a = std::make_shared<ImageArgs>();
  sub.add_option("image", a->request.image, "Input image (PNG or JPEG)")->required();
  sub.add_option("-o,--output", a->request.output, output_help)->required();
  add_network_options(sub, a->network, /*seeded=*/false);
  return a;
}

const CommandRegistration upscale{
    "upscale", "Super-resolve an image x4 with Real-ESRGAN (alpha is upscaled too)", [](CLI::App& sub) {
      auto a = add_image_options(sub, "Output image (.png keeps the alpha)");
      return [a] {
        ImageRequest request = a->request;
        request.network = a->network.resolved();
        print_stage_summary(upscale_image(request));
      };
    }};

const CommandRegistration matte{
    "matte",
    "Remove an image's background as `generate` does (U^2-Net or ISNet with rembg's cut-out, the mask made solid)",
    [](CLI::App& sub) {
      auto a = add_image_options(sub, "Output image with the background transparent (.png)");
      add_raw_matte_flag(sub, a->raw_matte);
      return [a] {
        ImageRequest request = a->request;
        request.network = a->network.resolved();
        print_stage_summary(remove_background(request, a->raw_matte));
      };
    }};

struct RefineArgs {
  RefineRequest request;
  NetworkArgs network;
};

const CommandRegistration refine{
    "refine", "Redraw four views at twice their size with ControlNet-tile and IP-Adapter (the official refine_rgb)",
    [](CLI::App& sub) {
      auto a = std::make_shared<RefineArgs>();
      RefineRequest& r = a->request;
      sub.add_option("views_dir", r.views_dir, "Folder with {front,right,back,left}_rgb.png (as `multiview` writes)")
          ->required();
      sub.add_option("-o,--output", r.output_dir, "Output folder: the refined {view}_rgb.png (512 px by default)")->required();
      sub.add_option("--front", r.front,
                     "The photo `multiview` drew from, prepared as `generate` prepares it for the IP-Adapter")
          ->required();
      sub.add_flag("--prepared", r.prepared_front,
                   "--front is already prepared (front.png of `generate --keep-intermediates`): use it as it is");
      add_raw_matte_flag(sub, r.raw_matte);
      add_network_options(sub, a->network);
      sub.add_option("--steps", r.options.steps, "Steps of the schedule, of which the last steps x strength run")
          ->capture_default_str()
          ->check(CLI::Range(1, 1000));
      sub.add_option("--strength", r.options.strength, "How much of the schedule runs (0.2 redraws fine detail only)")
          ->capture_default_str()
          ->check(number_in(0.0, 1.0));
      sub.add_option("--size", r.options.size, "Side of the 2x2 grid of views the pass redraws (each view comes "
                                               "back at half of it)")
          ->capture_default_str()
          ->check(CLI::Range(32, 8192));
      return [a] {
        RefineRequest request = a->request;
        request.network = a->network.resolved();
        print_stage_summary(refine_views(request));
      };
    }};

}  // namespace
}  // namespace u3d::cli
