#pragma once
// The options that shape the output mesh, shared by `reconstruct` and `generate`: --faces, --colour,
// --texture-size and --texture-format (docs/file_formats.md, "Textures").
#include <CLI/CLI.hpp>
#include <string>

#include "io/image_codec.h"
#include "isomer/reconstruct.h"
#include "pipeline/reconstruct.h"

namespace u3d::cli {

struct MeshOutputArgs {
  std::string colour = "texture";
  std::string texture_format = "png";
  CLI::Option* texture_size = nullptr;
  CLI::Option* texture_format_option = nullptr;
};

// Adds the options to `sub`; --faces and --texture-size write straight into `options`.
void add_mesh_output_options(CLI::App& sub, MeshOutputArgs& args, ReconstructOptions& options);

// Folds the parsed options into the reconstruction options and the texture format; an Error when a
// texture option comes without --colour texture.
void apply_mesh_output_options(const MeshOutputArgs& args, ReconstructOptions& options, TextureFormat& format);

// "texture: 2048^2, 212 charts, 71.3 % of the texels used, 96.1 % of those from the views; UV 0.21 s,
// baking 1.05 s" (nothing for vertex colours).
void print_texture_summary(const ReconstructOptions& options, const ReconstructSummary& summary);

}  // namespace u3d::cli
