// `unique3d multiview IMAGE -o DIR --models M`: the multi-view model's four views of an object photo
// (pipeline/multiview_stage.h).
#include "cli/command.h"
#include "cli/network_options.h"
#include "pipeline/multiview_stage.h"

namespace u3d::cli {
namespace {

struct MultiViewArgs {
  MultiViewRequest request;
  NetworkArgs network;
};

const CommandRegistration registration{
    "multiview", "Generate four views (front, right, back, left; 256 px by default) of an object photo, as `generate` draws them", [](CLI::App& sub) {
      auto args = std::make_shared<MultiViewArgs>();
      MultiViewRequest& r = args->request;
      sub.add_option("image", r.image,
                     "The photo (PNG or JPEG), prepared as `generate` prepares it: background removed when it has "
                     "none, cropped to the object, padded to a square on white")
          ->required();
      sub.add_flag("--prepared", r.prepared,
                   "The image is already prepared (front.png of `generate --keep-intermediates`): use it as it is");
      add_raw_matte_flag(sub, r.raw_matte);
      sub.add_option("-o,--output", r.output_dir, "Output folder: {front,right,back,left}_rgb.png")->required();
      add_network_options(sub, args->network);
      sub.add_option("--steps", r.options.steps, "Denoising steps")->capture_default_str()->check(CLI::Range(1, 1000));
      sub.add_option("--guidance", r.options.guidance_scale, "Classifier-free guidance scale")
          ->capture_default_str()
          ->check(number_in(0.0, 100.0));
      sub.add_option("--size", r.options.size,
                     "Side of the views; the model was trained at this default, and smaller is faster and worse")
          ->capture_default_str()
          ->check(CLI::Range(16, 4096));
      return [args] {
        MultiViewRequest request = args->request;
        request.network = args->network.resolved();
        print_stage_summary(generate_views(request));
      };
    }};

}  // namespace
}  // namespace u3d::cli
