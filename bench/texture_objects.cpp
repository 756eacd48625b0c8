// The texture atlas on every shared object, in one process: the `full` row of bench_objects (views
// rendered as `unique3d render --res R --fill 0.9` writes them, read back from the PNG files,
// `reconstruct` with its defaults: 40k faces, a 2048 texture baked from the views, `eval --given-frame
// --gt-render-fill 0.9 --views`), printing per object the atlas's charts, its texels used (the share of
// the texture whose centre a chart triangle covers: the texels baking fills), the UV and baking
// seconds, the 24-view PSNR and SSIM (renders at --eval-res) and the PSNR in the input views
// (eval/input_view_psnr.h: the textured mesh rendered in each view at its resolution). The geometry
// (reconstructed up to the texture, 40k faces) is kept as <out>/<object>/geometry_<res>.ply and, with
// --reuse-geometry, read back instead of reconstructed, so two builds that differ only in the atlas or
// the baking compare on the same geometry. The textured mesh is evaluated as `reconstruct` writes it
// (<out>/<object>/textured_<res>.glb, 8 bits a channel). Not a Google Benchmark. Usage: bench_texture_objects --help.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "core/image.h"
#include "core/view_set.h"
#include "eval/evaluate.h"
#include "io/mesh_io.h"
#include "isomer/reconstruct.h"
#include "isomer/texture_bake.h"
#include "render/render_view.h"

namespace fs = std::filesystem;
using namespace u3d;

int main(int argc, char** argv) {
  CLI::App app{"Reconstruct every shared object with a baked texture; print texels used and PSNR per object"};
  std::string objects_dir = (fs::path(UNIQUE3D_SOURCE_DIR) / ".." / "shared" / "data" / "objects").string();
  std::string out_dir = "bench_texture_objects_out";
  std::vector<std::string> only;
  int resolution = 512;
  int eval_resolution = AppearanceOptions{}.resolution;
  bool reuse_geometry = false;
  const float fill = 0.9f;
  app.add_option("--objects", objects_dir, "Folder of object folders (each with one mesh file)")->capture_default_str();
  app.add_option("--out", out_dir, "Folder for the rendered views")->capture_default_str();
  app.add_option("--only", only, "Object names to run (default: all)")->delimiter(',');
  app.add_option("--res", resolution, "View resolution")->capture_default_str();
  app.add_option("--eval-res", eval_resolution, "Resolution of the 24 evaluation renders (2x supersampled)")
      ->capture_default_str();
  app.add_flag("--reuse-geometry", reuse_geometry,
               "Read each object's geometry from <out>/<object>/geometry_<res>.ply when it is there (a previous "
               "run wrote it) instead of reconstructing it");
  CLI11_PARSE(app, argc, argv);
  if (!fs::is_directory(objects_dir)) {
    std::printf("bench_texture_objects: no objects folder at %s: nothing to do (skipped)\n", objects_dir.c_str());
    return 0;
  }
  std::vector<fs::path> objects;
  for (const auto& e : fs::directory_iterator(objects_dir))
    if (e.is_directory() && (only.empty() || std::find(only.begin(), only.end(), e.path().filename()) != only.end()))
      objects.push_back(e.path());
  std::sort(objects.begin(), objects.end());

  std::printf(
      "| object | faces | charts | texels used | UV (s) | baking (s) | PSNR | SSIM | input-view PSNR |\n"
      "|---|---|---|---|---|---|---|---|---|\n");
  double psnr_sum = 0, input_psnr_sum = 0;
  for (const fs::path& dir : objects) {
    fs::path mesh_path;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".obj") mesh_path = e.path();
    if (mesh_path.empty()) continue;
    const Mesh gt = read_mesh(mesh_path);
    Mesh placed = gt;
    normalize_to_unit_box(placed, fill);
    const fs::path views_dir = fs::path(out_dir) / dir.filename() / "views";
    fs::create_directories(views_dir);
    RenderSettings settings;
    settings.ssaa = 2;  // `unique3d render`'s default
    for (View v : kAllViews) {
      const RenderedView r = render_view(placed, view_camera(v, resolution), settings);
      save_image(r.rgb, views_dir / view_file_name(v, false));
      save_image(r.normal, views_dir / view_file_name(v, true));
    }
    const ViewSet views = load_view_set(views_dir);
    // `reconstruct` as it is up to the texture (the same decimation, vertex colours instead), then
    // the texture baked as `reconstruct` bakes it.
    ReconstructOptions options;
    const fs::path geometry_path = fs::path(out_dir) / dir.filename() / ("geometry_" + std::to_string(resolution) + ".ply");
    if (!reuse_geometry || !fs::exists(geometry_path)) {
      ReconstructOptions geometry_only = options;
      geometry_only.color_mode = ColorMode::Vertex;
      geometry_only.faces = final_face_count(options);
      Mesh geometry = reconstruct(views, geometry_only).mesh;
      geometry.colors.clear();
      write_mesh(geometry, geometry_path);
    }
    Mesh baked = read_mesh(geometry_path);
    const TextureBakeReport t = bake_texture(baked, views, options.coloring, options.texture);
    // Evaluated as `reconstruct` writes it: the texture in 8 bits per channel, read back from a GLB.
    const fs::path textured_path = fs::path(out_dir) / dir.filename() / ("textured_" + std::to_string(resolution) + ".glb");
    write_mesh(baked, textured_path);
    const Mesh mesh = read_mesh(textured_path);
    EvalOptions eval;
    eval.normalize = false;
    eval.gt_render_fill = fill;
    eval.appearance_options.resolution = eval_resolution;
    const EvalReport report = evaluate_meshes(mesh, gt, eval, &views);
    const int size = options.texture.atlas.texture_size;
    std::printf("| %s | %zu | %d | %.1f %% | %.2f | %.2f | %.2f | %.4f | %.3f |\n", dir.filename().c_str(),
                mesh.face_count(), t.charts, 100.0 * double(t.texels_covered) / (double(size) * size), t.uv_seconds,
                t.bake_seconds, report.appearance->psnr, report.appearance->ssim, report.input_view_psnr->mean);
    std::fflush(stdout);
    psnr_sum += report.appearance->psnr;
    input_psnr_sum += report.input_view_psnr->mean;
  }
  if (!objects.empty())
    std::printf("\nmean PSNR %.3f dB, input-view PSNR %.3f dB over %zu objects\n", psnr_sum / double(objects.size()),
                input_psnr_sum / double(objects.size()), objects.size());
  return 0;
}
