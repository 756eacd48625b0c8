#include "isomer/reconstruct.h"

#include <map>
#include <optional>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/quadric_decimation.h"

namespace u3d {

Mesh stage_initial_mesh(const ViewSet& views, const ReconstructOptions& options, bool* fitted) {
  if (fitted) *fitted = false;
  if (options.visual_hull) return carve_visual_hull(views, options.hull);
  if (options.sphere_init) return sphere_initial_mesh();
  Mesh initial = build_initial_mesh(views, options.init);
  const SilhouetteFitOptions& fit = options.silhouette_fit;
  if (!fit.enabled) return initial;
  const size_t faces = size_t(options.init.target_faces);
  // A mesh that misses most of a mask is fitted to the masks; one with more pieces than the masks'
  // hull is joined and cut by that hull.
  std::optional<Mesh> replaced = min_silhouette_iou(initial, views) < fit.initial_min_iou
                                     ? fit_to_silhouettes(initial, views, fit.resolution, faces)
                                     : start_for_extra_pieces(initial, views, fit, faces);
  if (!replaced) return initial;
  if (fitted) *fitted = true;
  return std::move(*replaced);
}

size_t final_face_count(const ReconstructOptions& options) {
  if (options.faces > 0) return options.faces;
  return options.color_mode == ColorMode::Texture ? kDefaultTextureFaces : 0;
}

ReconstructResult reconstruct(const ViewSet& views, const ReconstructOptions& options) {
  ReconstructResult result;
  auto timed = [&](const std::string& name, auto&& stage) {
    StageTimer timer(name);
    stage();
    result.timings.push_back({name, timer.finish()});
  };
  Mesh mesh;
  const char* start = options.visual_hull ? "visual hull" : options.sphere_init ? "sphere" : "initial mesh";
  bool fitted = false;  // the mesh is the silhouette fit's, not changed since
  timed(start, [&] { mesh = stage_initial_mesh(views, options, &fitted); });
  if (options.run_coarse || options.run_refine) {
    // Both stages work below the input resolution (by default both at 512 px): encode the maps and
    // downsample each working resolution once, inside the first stage's time. At 2048 px input this
    // saves about half a second per stage.
    std::optional<NormalViews> maps;
    std::map<int, NormalViews> working;
    auto working_views = [&](int resolution) -> const NormalViews& {
      auto it = working.find(resolution);
      if (it == working.end()) {
        if (!maps) maps = normal_views(views);
        it = working.emplace(resolution, at_resolution(*maps, resolution)).first;
      }
      return it->second;
    };
    fitted = false;
    if (options.run_coarse)
      timed("coarse", [&] { mesh = run_coarse_stage(mesh, working_views(kCoarseMapResolution), options.coarse, &result.coarse); });
    if (options.run_refine)
      timed("refine", [&] {
        mesh = run_refine_stage(mesh, working_views(options.refine.render_resolution), options.refine, &result.refine);
      });
  }
  // Smoothing and subdivision thin plates out and can take a mesh off its masks; the fit then starts
  // from the mesh as optimised (fitted meshes are not smoothed: the grid has already done so).
  Mesh smoothed;
  timed("smooth and subdivide", [&] { smoothed = fitted ? mesh : smooth_and_subdivide(mesh, options.cleanup); });
  const SilhouetteFitOptions& fit = options.silhouette_fit;
  bool grid_surface = fitted;  // a surface from the fit's grid, which can leave crumbs
  if (fit.enabled && (options.run_coarse || options.run_refine))
    timed("silhouette fit", [&] {
      if (std::optional<Mesh> fitted_mesh = fit_optimised_mesh(mesh, smoothed, views, fit)) {
        smoothed = std::move(*fitted_mesh);
        grid_surface = true;
      }
    });
  mesh = std::move(smoothed);
  const size_t faces = final_face_count(options);
  if (faces > 0 && mesh.faces.size() > faces)
    timed("decimate", [&] {
      mesh = decimate_closed_mesh(mesh, faces);
      if (mesh.faces.size() > faces + faces / 100)
        progress("warning: decimation stopped at " + std::to_string(mesh.faces.size()) + " faces (asked for " +
                 std::to_string(faces) + ")");
    });
  // After the decimation: removing pieces first changed the order of its collapses, and on signpost's
  // fit that order left the mesh open.
  if (grid_surface) drop_pieces_no_view_needs(mesh, views);
  if (options.color_mode == ColorMode::Texture)
    timed("texture", [&] {
      result.texture = bake_texture(mesh, views, options.coloring, options.texture);
      result.coloring = result.texture.vertices;
    });
  else
    timed("colouring", [&] { result.coloring = color_mesh(mesh, views, options.coloring); });
  mesh.validate("reconstructed mesh");
  result.mesh = std::move(mesh);
  return result;
}

}  // namespace u3d
