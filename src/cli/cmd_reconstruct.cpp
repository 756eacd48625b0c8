// `unique3d reconstruct VIEWS_DIR -o out.glb`: ISOMER from four views (RGB + normal maps) to a
// coloured mesh. The options become a ReconstructRequest for the library (pipeline/reconstruct.h), which
// checks everything before any work and writes atomically; this file prints its summary.
#include <cstdio>

#include "cli/command.h"
#include "cli/mesh_output_options.h"
#include "cli/reconstruct_options.h"
#include "pipeline/reconstruct.h"

namespace u3d::cli {
namespace {

void run(const ReconstructArgs& args) {
  const ReconstructRequest request = make_reconstruct_request(args);
  const ReconstructSummary s = reconstruct_folder(request);
  std::printf("mesh: %zu vertices, %zu faces, %s\n", s.mesh.vertex_count(), s.mesh.face_count(),
              s.topology.summary().c_str());
  std::printf("colouring: %zu vertices from the views, %zu completed, %zu unreachable\n", s.coloring.confident,
              s.coloring.completed, s.coloring.unreachable);
  print_texture_summary(request.options, s);
  const std::array<float, 4>& iou = s.silhouette_iou;
  std::printf("silhouette IoU: front %.4f, right %.4f, back %.4f, left %.4f\n", iou[0], iou[1], iou[2], iou[3]);
  std::printf("time:");
  for (size_t i = 0; i < s.timings.size(); ++i)
    std::printf("%s %s %.2f s", i ? "," : "", s.timings[i].name.c_str(), s.timings[i].seconds);
  std::printf(", total %.2f s\n", s.total_seconds());
}

const CommandRegistration registration{
    "reconstruct", "ISOMER: reconstruct a textured mesh from four views (RGB + normal maps)", [](CLI::App& sub) {
      auto args = std::make_shared<ReconstructArgs>();
      sub.add_option("views_dir", args->request.views_dir,
                     "Folder with front/right/back/left _rgb.png and _normal.png (as `unique3d render` writes)")
          ->required();
      sub.add_option("-o,--output", args->request.output, "Output mesh (.glb, .obj or .ply)")->required();
      sub.add_flag("--preview", args->request.previews,
                   "Also write <output>_views.png (the four views) and <output>_turntable.png");
      add_reconstruct_options(sub, *args);
      return [args] { run(*args); };
    }};

}  // namespace
}  // namespace u3d::cli
