#include "cli/mesh_output_options.h"

#include <cstdio>

#include "core/error.h"

namespace u3d::cli {

void add_mesh_output_options(CLI::App& sub, MeshOutputArgs& args, ReconstructOptions& options) {
  sub.add_option("--faces", options.faces,
                 "Decimate the final mesh to this many faces (default: " + std::to_string(kDefaultTextureFaces) +
                     " with --colour texture, the mesh as reconstructed with vertex colours)")
      ->check(CLI::Range(size_t(100), size_t(100000000)));
  sub.add_option("--colour", args.colour,
                 "Colour as per-vertex colours or as a texture baked from the full-resolution views")
      ->capture_default_str()
      ->check(CLI::IsMember({"vertex", "texture"}));
  args.texture_size = sub.add_option("--texture-size", options.texture.atlas.texture_size,
                                     "Texels per side of the baked texture (with --colour texture)")
                          ->capture_default_str()
                          ->check(CLI::Range(64, 8192));
  args.texture_format_option =
      sub.add_option("--texture-format", args.texture_format, "Texture file format (with --colour texture): png or jpg")
          ->capture_default_str()
          ->check(CLI::IsMember({"png", "jpg"}));
}

void apply_mesh_output_options(const MeshOutputArgs& args, ReconstructOptions& options, TextureFormat& format) {
  options.color_mode = args.colour == "texture" ? ColorMode::Texture : ColorMode::Vertex;
  if (options.color_mode == ColorMode::Vertex) {
    require(args.texture_size->count() == 0, "--texture-size needs --colour texture");
    require(args.texture_format_option->count() == 0, "--texture-format needs --colour texture");
  }
  format = parse_texture_format(args.texture_format);
}

void print_texture_summary(const ReconstructOptions& options, const ReconstructSummary& summary) {
  if (options.color_mode != ColorMode::Texture) return;
  const TextureBakeReport& t = summary.texture;
  const int size = options.texture.atlas.texture_size;
  std::printf(
      "texture: %dx%d, %d charts, %.1f %% of the texels used, %.1f %% of those from the views; UV %.2f s, "
      "baking %.2f s\n",
      size, size, t.charts, 100.0 * t.texel_efficiency,
      t.texels_covered ? 100.0 * double(t.texels_confident) / double(t.texels_covered) : 0.0, t.uv_seconds,
      t.bake_seconds);
}

}  // namespace u3d::cli
