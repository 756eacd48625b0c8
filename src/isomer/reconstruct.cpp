#include "isomer/reconstruct.h"

#include <map>
#include <optional>

#include "core/error.h"
#include "core/progress.h"
#include "isomer/view_resolution.h"

namespace u3d {
namespace {

StageMesh to_stage_mesh(const Mesh& mesh) { return {mesh.positions, mesh.faces}; }

// Only geometry survives an optimisation stage; colours come later from the views.
Mesh from_stage_mesh(StageMesh stage) {
  Mesh mesh;
  mesh.positions = std::move(stage.positions);
  mesh.faces = std::move(stage.faces);
  return mesh;
}

}  // namespace

StageViews stage_views(const ViewSet& views) {
  StageViews out;
  for (View v : kAllViews) {
    const Image& decoded = views[v].normals;
    Image encoded(decoded.width, decoded.height, 4);
    const int64_t pixels = int64_t(decoded.pixel_count());
#pragma omp parallel for schedule(static) if (pixels > 65536)
    for (int64_t p = 0; p < pixels; ++p) {
      const float* in = decoded.data.data() + p * 4;
      float* px = encoded.data.data() + p * 4;
      for (int c = 0; c < 3; ++c) px[c] = 0.5f * (in[c] + 1.f);
      px[3] = in[3];
    }
    out.normal_maps.push_back(std::move(encoded));
    out.cameras.push_back(view_camera(v, decoded.width));
  }
  return out;
}

Mesh stage_initial_mesh(const ViewSet& views, const ReconstructOptions& options) {
  if (options.visual_hull) return carve_visual_hull(views, options.hull);
  if (options.sphere_init) return from_stage_mesh(sphere_initial_mesh());
  return build_initial_mesh(views, options.init);
}

Mesh stage_coarse(const Mesh& mesh, const StageViews& views, const ReconstructOptions& options,
                  StageReport* report) {
  const ViewsAtResolution coarse = views_at_resolution(views.normal_maps, views.cameras, kCoarseMapResolution);
  return from_stage_mesh(
      run_coarse_stage(to_stage_mesh(mesh), coarse.normal_maps, coarse.cameras, options.coarse, report));
}

Mesh stage_refine(const Mesh& mesh, const StageViews& views, const ReconstructOptions& options,
                  StageReport* report) {
  return from_stage_mesh(
      run_refine_stage(to_stage_mesh(mesh), views.normal_maps, views.cameras, options.refine, report));
}

Mesh stage_smooth_and_subdivide(const Mesh& mesh, const ReconstructOptions& options) {
  return smooth_and_subdivide(mesh, options.cleanup);
}

ColouringReport stage_colouring(Mesh& mesh, const ViewSet& views, const ReconstructOptions& options) {
  return colour_mesh(mesh, views, options.colouring);
}

void stage_output_transform(Mesh& mesh, const ReconstructOptions& options) {
  if (!options.official_output_scale) return;
  for (Vec3f& p : mesh.positions) p *= kOfficialOutputScale;
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
  timed(start, [&] { mesh = stage_initial_mesh(views, options); });
  if (options.run_coarse || options.run_refine) {
    // Both stages work below the input resolution (by default both at 512 px): encode the maps and
    // downsample each working resolution once, inside the first stage's time. At 2048 px input this
    // saves about half a second per stage.
    std::optional<StageViews> maps;
    std::map<int, StageViews> working;
    auto at_resolution = [&](int resolution) -> const StageViews& {
      auto it = working.find(resolution);
      if (it == working.end()) {
        if (!maps) maps = stage_views(views);
        ViewsAtResolution v = views_at_resolution(maps->normal_maps, maps->cameras, resolution);
        it = working.emplace(resolution, StageViews{std::move(v.normal_maps), std::move(v.cameras)}).first;
      }
      return it->second;
    };
    if (options.run_coarse)
      timed("coarse", [&] { mesh = stage_coarse(mesh, at_resolution(kCoarseMapResolution), options, &result.coarse); });
    if (options.run_refine)
      timed("refine", [&] {
        mesh = stage_refine(mesh, at_resolution(options.refine.render_resolution), options, &result.refine);
      });
  }
  timed("smooth and subdivide", [&] { mesh = stage_smooth_and_subdivide(mesh, options); });
  timed("colouring", [&] { result.colouring = stage_colouring(mesh, views, options); });
  stage_output_transform(mesh, options);
  mesh.validate("reconstructed mesh");
  result.mesh = std::move(mesh);
  return result;
}

}  // namespace u3d
