#include "cli/reconstruct_options.h"

#include "core/view_set.h"

namespace u3d::cli {

void add_reconstruct_options(CLI::App& sub, ReconstructArgs& args) {
  ReconstructOptions& o = args.request.options;
  sub.add_option("--normal-space", args.normal_space, "Space of the normal maps: world or camera")
      ->capture_default_str()
      ->check(CLI::IsMember({"world", "camera"}));
  sub.add_flag("--official-scale", args.request.official_output_scale,
               "Scale the output by 0.675 like the official release (default: the views' frame, unscaled)");
  sub.add_option("--init-resolution", o.init.integration_resolution,
                 "Resolution at which normal maps are integrated for the initial mesh")
      ->capture_default_str()
      ->check(CLI::Range(16, 4096));
  sub.add_option("--init-faces", o.init.target_faces, "Face count of the initial mesh")
      ->capture_default_str()
      ->check(CLI::Range(100, 10000000));
  CLI::Option* init_only = sub.add_flag(
      "--init-only", args.init_only, "Ablation: skip both optimisation stages (initial mesh -> clean-up -> colouring)");
  CLI::Option* visual_hull = sub.add_flag(
      "--visual-hull", o.visual_hull,
      "Baseline: the visual hull carved from the four masks instead of initial mesh and optimisation "
      "(visual hull -> clean-up -> colouring)");
  visual_hull->excludes(init_only);
  sub.add_option("--hull-resolution", o.hull.resolution, "Voxels per axis of the --visual-hull grid over [-1,1]^3")
      ->capture_default_str()
      ->check(CLI::Range(4, 1024))
      ->needs(visual_hull);
  sub.add_option("--refine-target", args.refine_target,
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
  add_isomer_step_options(sub, args.steps);
  args.steps.no_fit->excludes(visual_hull);
  for (CLI::Option* steps : {args.steps.coarse, args.steps.refine}) steps->excludes(init_only)->excludes(visual_hull);
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
  add_mesh_output_options(sub, args.output, o);
}

ReconstructRequest make_reconstruct_request(const ReconstructArgs& args) {
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

}  // namespace u3d::cli
