#include "cli/isomer_options.h"

#include <string>

namespace u3d::cli {

void add_isomer_step_options(CLI::App& sub, IsomerStepArgs& args) {
  args.coarse = sub.add_option("--coarse-steps", args.coarse_steps,
                               "Steps of the coarse stage (default: " + std::to_string(CoarseStageOptions{}.steps) +
                                   ")")
                    ->check(CLI::Range(0, 100000));
  args.refine = sub.add_option("--refine-steps", args.refine_steps,
                               "Steps of the refinement stage (default: " +
                                   std::to_string(RefineStageOptions{}.steps) + ")")
                    ->check(CLI::Range(0, 100000));
  args.no_fit = sub.add_flag("--no-silhouette-fit", args.no_silhouette_fit,
                             "Ablation: never fit the mesh to the visual hull of the masks (neither the initial "
                             "mesh nor the optimised one)");
}

void apply_isomer_step_options(const IsomerStepArgs& args, ReconstructOptions& options) {
  if (args.coarse_steps >= 0) options.coarse.steps = args.coarse_steps;
  if (args.refine_steps >= 0) options.refine.steps = args.refine_steps;
  if (args.no_silhouette_fit) options.silhouette_fit.enabled = false;
}

}  // namespace u3d::cli
