#pragma once
// The options of `unique3d reconstruct` that shape its result (all but the views folder, -o and --preview),
// shared with `unique3d batch`, which applies them to every view folder (and the ISOMER stage of every
// photo) of a batch.
#include <CLI/CLI.hpp>
#include <string>

#include "cli/isomer_options.h"
#include "cli/mesh_output_options.h"
#include "pipeline/reconstruct.h"

namespace u3d::cli {

struct ReconstructArgs {
  std::string normal_space = "world";
  bool init_only = false;
  std::string refine_target = "multiview";
  IsomerStepArgs steps;
  MeshOutputArgs output;
  ReconstructRequest request;
};

// Adds the options to `sub`; `args` must outlive the parse (a flag's function writes into it).
void add_reconstruct_options(CLI::App& sub, ReconstructArgs& args);

// The request the parsed options make (views_dir, output and previews as in args.request): the ablation
// flags folded into the stage options (--sphere-init brings the sphere schedule, which an explicit
// --coarse-steps still overrides), the mesh output options applied.
ReconstructRequest make_reconstruct_request(const ReconstructArgs& args);

}  // namespace u3d::cli
