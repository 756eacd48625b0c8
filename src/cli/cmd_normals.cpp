// `unique3d normals VIEWS_DIR -o DIR --models M`: normal maps for four views, written as a view set that
// `unique3d reconstruct` takes (pipeline/normal_stage.h).
#include "cli/command.h"
#include "cli/network_options.h"
#include "pipeline/normal_stage.h"

namespace u3d::cli {
namespace {

struct NormalArgs {
  NormalRequest request;
  std::filesystem::path front;
  NetworkArgs network;
  bool no_upscale = false;
};

const CommandRegistration registration{
    "normals", "Predict a normal map per view and write the view set ISOMER reconstructs from", [](CLI::App& sub) {
      auto args = std::make_shared<NormalArgs>();
      NormalRequest& r = args->request;
      sub.add_option("views_dir", r.views_dir, "Folder with {front,right,back,left}_rgb.png (as `multiview` writes)")
          ->required();
      sub.add_option("-o,--output", r.output_dir,
                     "Output folder: the view set, {view}_rgb.png with masks and world-space {view}_normal.png")
          ->required();
      sub.add_option("--front", args->front,
                     "Use this photo as the front view instead of front_rgb.png, prepared as `generate` prepares "
                     "it (background removed when it has none, cropped to the object and made square), as "
                     "`generate` does with the input photo");
      sub.add_flag("--prepared", r.prepared_front,
                   "--front is already prepared (front.png of `generate --keep-intermediates`): use it as it is")
          ->needs("--front");
      add_raw_matte_flag(sub, r.raw_matte);
      add_network_options(sub, args->network);
      sub.add_option("--steps", r.options.steps, "Denoising steps")->capture_default_str()->check(CLI::Range(1, 1000));
      sub.add_option("--guidance", r.options.guidance_scale, "Classifier-free guidance scale")
          ->capture_default_str()
          ->check(number_in(0.0, 100.0));
      sub.add_option("--size", r.options.size,
                     "Side of the model's input and output; it was trained at this default, and smaller is "
                     "faster and worse")
          ->capture_default_str()
          ->check(CLI::Range(16, 4096));
      sub.add_flag("--no-upscale", args->no_upscale, "Keep the normal maps at the model's size (--size; no Real-ESRGAN x4)");
      return [args] {
        NormalRequest request = args->request;
        if (!args->front.empty()) request.front = args->front;
        request.options.upscale = !args->no_upscale;
        request.network = args->network.resolved();
        print_stage_summary(predict_view_normals(request));
      };
    }};

}  // namespace
}  // namespace u3d::cli
