// `unique3d reconstruct VIEWS_DIR -o out.glb`: ISOMER from four views (RGB + normal maps) to a
// coloured mesh. Input is validated completely before any work; outputs are written atomically and
// only after everything succeeded.
#include <cstdio>
#include <filesystem>

#include "cli/command.h"
#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh_topology.h"
#include "io/mesh_io.h"
#include "isomer/reconstruct.h"
#include "isomer/silhouette_check.h"
#include "render/preview.h"

namespace u3d::cli {
namespace {

struct ReconstructArgs {
  std::string views_dir;
  std::string output;
  std::string normal_space = "world";
  bool preview = false;
  bool init_only = false;
  bool no_explicit_target = false;
  int coarse_steps = -1;  // -1: the schedule's own
  int refine_steps = -1;
  ReconstructOptions options;
};

// The ablation flags, folded into the stage options (--sphere-init brings the sphere schedule, which
// an explicit --coarse-steps still overrides).
ReconstructOptions stage_options(const ReconstructArgs& args) {
  ReconstructOptions o = args.options;
  if (o.sphere_init) o.coarse = CoarseStageOptions::from_sphere();
  if (args.coarse_steps >= 0) o.coarse.steps = args.coarse_steps;
  if (args.refine_steps >= 0) o.refine.steps = args.refine_steps;
  o.refine.use_explicit_target = !args.no_explicit_target;
  o.run_coarse = o.run_refine = !args.init_only && !o.visual_hull;
  return o;
}

std::string lower_extension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::filesystem::path with_suffix(const std::filesystem::path& output, const std::string& suffix) {
  return output.parent_path() / (output.stem().string() + suffix);
}

void run(const ReconstructArgs& args) {
  const std::filesystem::path out(args.output);
  const std::string ext = lower_extension(out);
  require(ext == ".glb" || ext == ".obj" || ext == ".ply",
          "output " + args.output + ": unsupported extension (use .glb, .obj or .ply)");
  const std::filesystem::path out_dir = out.parent_path().empty() ? "." : out.parent_path();
  require(std::filesystem::is_directory(out_dir), "output folder " + out_dir.string() + " does not exist");

  StageTimer load_timer("loading views");
  const ViewSet views = load_view_set(args.views_dir, parse_normal_space(args.normal_space));
  const double load_seconds = load_timer.finish();

  ReconstructResult result = reconstruct(views, stage_options(args));

  // Quality report against the input, in the views' frame (before any output scale).
  Mesh in_view_frame = result.mesh;
  if (args.options.official_output_scale)
    for (Vec3f& p : in_view_frame.positions) p /= kOfficialOutputScale;
  const MeshTopology topo = mesh_topology(result.mesh);
  const std::array<float, 4> iou = silhouette_iou(in_view_frame, views);

  StageTimer write_timer("writing " + args.output);
  write_mesh(result.mesh, out);
  const double write_seconds = write_timer.finish();
  double preview_seconds = 0.0;
  if (args.preview) {
    StageTimer preview_timer("rendering previews");
    save_image(preview_four_views(in_view_frame), with_suffix(out, "_views.png"));
    save_image(preview_turntable(in_view_frame), with_suffix(out, "_turntable.png"));
    preview_seconds = preview_timer.finish();
  }

  std::printf("mesh: %zu vertices, %zu faces, %s\n", result.mesh.vertex_count(), result.mesh.face_count(),
              topo.summary().c_str());
  std::printf("colouring: %zu vertices from the views, %zu completed, %zu unreachable\n", result.colouring.confident,
              result.colouring.completed, result.colouring.unreachable);
  std::printf("silhouette IoU: front %.4f, right %.4f, back %.4f, left %.4f\n", iou[0], iou[1], iou[2], iou[3]);
  std::printf("time: load %.2f s", load_seconds);
  double total = load_seconds + write_seconds + preview_seconds;
  for (const StageTiming& t : result.timings) {
    std::printf(", %s %.2f s", t.name.c_str(), t.seconds);
    total += t.seconds;
  }
  std::printf(", write %.2f s", write_seconds);
  if (args.preview) std::printf(", previews %.2f s", preview_seconds);
  std::printf(", total %.2f s\n", total);
}

const CommandRegistration registration{
    "reconstruct", "ISOMER: reconstruct a coloured mesh from four views (RGB + normal maps)", [](CLI::App& sub) {
      auto args = std::make_shared<ReconstructArgs>();
      ReconstructOptions& o = args->options;
      sub.add_option("views_dir", args->views_dir,
                     "Folder with front/right/back/left _rgb.png and _normal.png (as `unique3d render` writes)")
          ->required();
      sub.add_option("-o,--output", args->output, "Output mesh (.glb, .obj or .ply)")->required();
      sub.add_option("--normal-space", args->normal_space, "Space of the normal maps: world or camera")
          ->capture_default_str()
          ->check(CLI::IsMember({"world", "camera"}));
      sub.add_flag("--preview", args->preview,
                   "Also write <output>_views.png (the four views) and <output>_turntable.png");
      sub.add_flag("--official-scale", o.official_output_scale,
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
      sub.add_flag("--no-explicit-target", args->no_explicit_target,
                   "Ablation: refine with the plain multi-view normal loss instead of ExplicitTarget normals")
          ->excludes(init_only)
          ->excludes(visual_hull);
      sub.add_flag("--sphere-init", o.sphere_init,
                   "Start the coarse stage from a sphere (official sphere schedule) instead of the initial mesh")
          ->excludes(init_only)
          ->excludes(visual_hull);
      sub.add_option("--coarse-steps", args->coarse_steps,
                     "Steps of the coarse stage (default: " + std::to_string(CoarseStageOptions{}.steps) + ")")
          ->check(CLI::Range(0, 100000))
          ->excludes(init_only)
          ->excludes(visual_hull);
      sub.add_option("--refine-steps", args->refine_steps,
                     "Steps of the refinement stage (default: " + std::to_string(RefineStageOptions{}.steps) + ")")
          ->check(CLI::Range(0, 100000))
          ->excludes(init_only)
          ->excludes(visual_hull);
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
      sub.add_option("--visibility-resolution", o.colouring.target.raster_resolution,
                     "Raster resolution of the colouring visibility test")
          ->capture_default_str()
          ->check(CLI::Range(16, 8192));
      return [args] { run(*args); };
    }};

}  // namespace
}  // namespace u3d::cli
