#pragma once
// The ISOMER schedule options shared by `reconstruct` (and `batch`: cli/reconstruct_options.h) and
// `generate`: --coarse-steps, --refine-steps and --no-silhouette-fit. `reconstruct` adds its ablations
// on top.
#include <CLI/CLI.hpp>

#include "isomer/reconstruct.h"

namespace u3d::cli {

struct IsomerStepArgs {
  int coarse_steps = -1;  // -1: the schedule's own
  int refine_steps = -1;
  bool no_silhouette_fit = false;
  CLI::Option* coarse = nullptr;  // the options, for the commands' own excludes()
  CLI::Option* refine = nullptr;
  CLI::Option* no_fit = nullptr;
};

void add_isomer_step_options(CLI::App& sub, IsomerStepArgs& args);

// Folds the parsed options into `options`, after any schedule the command chose (the sphere start).
void apply_isomer_step_options(const IsomerStepArgs& args, ReconstructOptions& options);

}  // namespace u3d::cli
