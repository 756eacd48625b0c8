#include "isomer/reconstruct.h"

#include "core/error.h"
#include "core/progress.h"

namespace u3d {

Mesh stage_initial_mesh(const ViewSet& views, const ReconstructOptions& options) {
  return build_initial_mesh(views, options.init);
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
  timed("initial mesh", [&] { mesh = stage_initial_mesh(views, options); });
  timed("smooth and subdivide", [&] { mesh = stage_smooth_and_subdivide(mesh, options); });
  timed("colouring", [&] { result.colouring = stage_colouring(mesh, views, options); });
  stage_output_transform(mesh, options);
  mesh.validate("reconstructed mesh");
  result.mesh = std::move(mesh);
  return result;
}

}  // namespace u3d
