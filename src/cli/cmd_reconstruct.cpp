// `unique3d reconstruct VIEWS_DIR -o out.glb`: ISOMER from four views (RGB + normal maps) to a
// coloured mesh. The options become a ReconstructRequest for the library (pipeline/reconstruct.h), which
// checks everything before any work and writes atomically; this file prints its summary.
#include <cstdio>

#include "cli/command.h"
#include "cli/isomer_options.h"
#include "cli/mesh_output_options.h"
#include "core/view_set.h"
#include "pipeline/reconstruct.h"

namespace u3d::cli {
namespace {

struct ReconstructArgs {
  std::string normal_space = "world";
  bool init_only = false;
  std::string refine_target = "multiview";
  IsomerStepArgs steps;
  MeshOutputArgs output;
  ReconstructRequest request;
};

// The ablation flags, folded into the stage options (--sphere-init brings the sphere schedule, which
// an explicit --coarse-steps still overrides).
ReconstructRequest make_request(const ReconstructArgs& args) {
  ReconstructRequest r = args.request;
  r.normal_space = parse_normal_space(args.normal_space);
  ReconstructOptions& o = r.options;
  if (o.sphere_init) o.coarse = CoarseStageOptions::from_sphere();
  apply_isomer_step_options(args.steps, o);
  o.refine.target = args.refine_target == "multiview" ? RefineTarget::MultiView
                    : args.refine_target == "explicit" ? RefineTarget::ExplicitTarget
                                                       : RefineTarget::WhereViewsDisagree;
  o.run_coarse = o.run_refine = !args.init_only && !o.visual_hull;
  apply_mesh_output_options(args.output, o, r.texture_format);
  return r;
}

void run(const ReconstructArgs& args) {
  const ReconstructRequest request = make_request(args);
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
      ReconstructOptions& o = args->request.options;
      sub.add_option("views_dir", args->request.views_dir,
                     "Folder with front/right/back/left _rgb.png and _normal.png (as `unique3d render` writes)")
          ->required();
      sub.add_option("-o,--output", args->request.output, "Output mesh (.glb, .obj or .ply)")->required();
      sub.add_option("--normal-space", args->normal_space, "Space of the normal maps: world or camera")
          ->capture_default_str()
          ->check(CLI::IsMember({"world", "camera"}));
      sub.add_flag("--preview", args->request.previews,
                   "Also write <output>_views.png (the four views) and <output>_turntable.png");
      sub.add_flag("--official-scale", args->request.official_output_scale,
                   "Scale the output by 0.675 like the official release (default: the views' frame, unscaled)");
      sub.add_option("--init-resolution", o.init.integration_resolution,
                     "Resolution at which normal maps are integrated for the initial mesh")
          ->capture_default_str()
          ->check(CLI::Range(16, 4096));
      sub.add_option("--init-faces", o.init.target_faces, "Face count of the initial mesh")
          ->capture_default_str()
          ->check(CLI::Range(100, 10000000));
      CLI::Option* init_only = sub.add_flag(
          "--init-only", args->init_only, "Ablation: skip both optimisation stages (initial mesh -> clean-up -> colouring)");
      CLI::Option* visual_hull = sub.add_flag(
          "--visual-hull", o.visual_hull,
          "Baseline: the visual hull carved from the four masks instead of initial mesh and optimisation "
          "(visual hull -> clean-up -> colouring)");
      visual_hull->excludes(init_only);
      sub.add_option("--hull-resolution", o.hull.resolution, "Voxels per axis of the --visual-hull grid over [-1,1]^3")
          ->capture_default_str()
          ->check(CLI::Range(4, 1024))
          ->needs(visual_hull);
      sub.add_option("--refine-target", args->refine_target,
                     "What the refinement pulls each view's normals toward: 'multiview' (the view's own map; the "
                     "default, best on exact and on smoothly disagreeing views in docs/evaluation.md), 'explicit' "
                     "(the fused ExplicitTarget everywhere, as the official code), 'disagree' (ExplicitTarget only "
                     "where the views disagree by more than --disagreement-threshold)")
          ->capture_default_str()
          ->check(CLI::IsMember({"multiview", "explicit", "disagree"}))
          ->excludes(init_only)
          ->excludes(visual_hull);
      sub.add_option("--disagreement-threshold", o.refine.disagreement_threshold,
                     "With --refine-target disagree: RMS spread of the views' normals (about radians) above "
                     "which a vertex takes the fused target")
          ->capture_default_str()
          ->check(CLI::Range(0.f, 2.f))
          ->excludes(init_only)
          ->excludes(visual_hull);
      sub.add_flag("--sphere-init", o.sphere_init,
                   "Start the coarse stage from a sphere (official sphere schedule) instead of the initial mesh")
          ->excludes(init_only)
          ->excludes(visual_hull);
      add_isomer_step_options(sub, args->steps);
      args->steps.no_fit->excludes(visual_hull);
      for (CLI::Option* steps : {args->steps.coarse, args->steps.refine})
        steps->excludes(init_only)->excludes(visual_hull);
      sub.add_option("--refine-resolution", o.refine.render_resolution,
                     "Longest side the refinement renders the views at; larger normal maps are downsampled "
                     "(0 = the maps' own)")
          ->capture_default_str()
          ->check(CLI::Range(0, 8192))
          ->excludes(init_only)
          ->excludes(visual_hull);
      sub.add_option("--poisson-depth", o.init.poisson_depth, "Screened Poisson octree depth")
          ->capture_default_str()
          ->check(CLI::Range(4, 12));
      sub.add_option("--smooth", o.cleanup.smooth_iterations, "Laplacian smoothing steps before colouring")
          ->capture_default_str()
          ->check(CLI::Range(0, 100));
      sub.add_option("--subdivide", o.cleanup.subdivision_iterations, "Loop subdivision iterations before colouring")
          ->capture_default_str()
          ->check(CLI::Range(0, 4));
      sub.add_option("--visibility-resolution", o.coloring.target.raster_resolution,
                     "Raster resolution of the colouring visibility test")
          ->capture_default_str()
          ->check(CLI::Range(16, 8192));
      add_mesh_output_options(sub, args->output, o);
      return [args] { run(*args); };
    }};

}  // namespace
}  // namespace u3d::cli
