// unique3d eval PRED GT: geometry and appearance metrics of a reconstruction against ground truth.
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>

#include "cli/command.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/view_set.h"
#include "eval/eval_report.h"
#include "eval/evaluate.h"
#include "io/mesh_io.h"

namespace u3d::cli {
namespace {

// Above this --iou-resolution the occupancy grid takes minutes (1024: about 10^9 cells).
constexpr int kSlowIouResolution = 256;

struct EvalArgs {
  std::string pred_path, gt_path, json_path, save_renders, views_dir;
  bool given_frame = false;
  bool no_appearance = false;
  EvalOptions options;
};

void run_eval(const EvalArgs& a) {
  if (a.options.iou_resolution > kSlowIouResolution)
    progress("note: --iou-resolution " + std::to_string(a.options.iou_resolution) + " classifies " +
             std::to_string(static_cast<long long>(a.options.iou_resolution) * a.options.iou_resolution *
                            a.options.iou_resolution) +
             " grid cells per mesh; above " + std::to_string(kSlowIouResolution) + " this takes minutes");
  Mesh pred = read_mesh(a.pred_path);
  Mesh gt = read_mesh(a.gt_path);
  EvalOptions options = a.options;
  options.normalize = !a.given_frame;
  options.appearance = !a.no_appearance;
  options.save_renders_dir = a.save_renders;
  std::optional<ViewSet> views;
  if (!a.views_dir.empty()) views = load_view_set(a.views_dir);
  EvalReport report = evaluate_meshes(std::move(pred), std::move(gt), options, views ? &*views : nullptr);
  std::fputs(("pred: " + a.pred_path + "\ngt:   " + a.gt_path + "\n" + report_summary(report)).c_str(), stdout);
  if (!a.json_path.empty()) {
    nlohmann::json j = report_to_json(report);
    j["pred_file"] = a.pred_path;
    j["gt_file"] = a.gt_path;
    write_atomically(a.json_path, [&](const std::filesystem::path& tmp) {
      std::ofstream f(tmp);
      f << j.dump(2) << "\n";
      f.close();
      require(bool(f), "cannot write " + a.json_path);
    });
  }
}

const CommandRegistration registration{
    "eval",
    "Compare a reconstructed mesh with a ground-truth mesh (Chamfer, F-score, volume IoU, PSNR, SSIM, input masks)",
    [](CLI::App& sub) -> CommandAction {
      auto a = std::make_shared<EvalArgs>();
      sub.add_option("pred", a->pred_path, "Predicted mesh (.obj, .ply, .glb, .gltf)")->required()->check(CLI::ExistingFile);
      sub.add_option("gt", a->gt_path, "Ground-truth mesh")->required()->check(CLI::ExistingFile);
      sub.add_option("--json", a->json_path, "Also write all metrics to this JSON file");
      sub.add_flag("--given-frame", a->given_frame,
                   "Meshes share one frame: normalize both with the GT's transform instead of each on its own");
      sub.add_option("--gt-render-fill", a->options.gt_render_fill,
                     "With --given-frame: place the GT as `unique3d render --fill F` did (reconstructions from those views)")
          ->check(number_in(0.01, 1));
      sub.add_option("--samples", a->options.surface_samples, "Surface samples per mesh for Chamfer and F-score")
          ->capture_default_str()->check(CLI::Range(size_t(100), size_t(100000000)));
      sub.add_option("--fscore-thresholds", a->options.fscore_thresholds, "F-score distance thresholds")
          ->delimiter(',')->capture_default_str()->check(number_in(1e-6, 1));
      sub.add_option("--iou-resolution", a->options.iou_resolution, "Occupancy grid cells per axis for volume IoU (cost grows with its cube: above 256 it takes minutes)")
          ->capture_default_str()->check(CLI::Range(2, 1024));
      sub.add_option("--render-resolution", a->options.appearance_options.resolution, "Pixels per side of the 24 renders")
          ->capture_default_str()->check(CLI::Range(16, 4096));
      sub.add_option("--ssaa", a->options.appearance_options.ssaa,
                     "Supersampling per axis of the renders (the 24 views' and, with --views, the input views')")
          ->capture_default_str()->check(CLI::Range(1, 8));
      sub.add_flag("--no-appearance", a->no_appearance, "Skip the rendered PSNR/SSIM comparisons");
      sub.add_option("--views", a->views_dir,
                     "The view set PRED was reconstructed from (PRED in its frame): count mesh pixels over the masks' "
                     "background and mask pixels the mesh misses, per view, compare the mesh's pieces with the "
                     "masks' visual hull and, with appearance, render PRED in each view at its resolution for its "
                     "PSNR against the view's RGB over its mask")
          ->check(CLI::ExistingDirectory);
      sub.add_option("--save-renders", a->save_renders, "Write the 2 x 24 renders to this folder");
      sub.add_option("--seed", a->options.seed, "Seed of the surface sampling")->capture_default_str();
      return [a] { run_eval(*a); };
    }};

}  // namespace
}  // namespace u3d::cli
