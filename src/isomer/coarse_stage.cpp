#include "isomer/coarse_stage.h"

#include "core/progress.h"
#include "geometry/icosphere.h"
#include "isomer/mesh_optimizer.h"
#include "isomer/optimisation_loop.h"
#include "isomer/reconstruction_losses.h"

namespace u3d {

CoarseStageOptions CoarseStageOptions::from_sphere() {
  CoarseStageOptions o;
  o.start_edge_length = 0.15f;
  o.end_edge_length = 0.01f;
  o.gain = 0.1f;
  return o;
}

Mesh sphere_initial_mesh() { return make_icosphere(3, 0.5f); }

Mesh run_coarse_stage(const Mesh& initial, const NormalViews& input, const CoarseStageOptions& options,
                      StageReport* report) {
  StageTimer timer("coarse reconstruction");
  const NormalViews views = prepare_stage_views("coarse stage", input, options.render_resolution);
  const std::vector<NormalTarget> targets = normal_targets(views);
  std::vector<const Image*> references;
  for (const NormalTarget& t : targets) references.push_back(&t.rgba);

  MeshOptimizerOptions opt;
  opt.learning_rate = options.learning_rate;
  opt.min_edge_length = options.end_edge_length;
  opt.max_edge_length = options.start_edge_length;
  opt.gain = options.gain;
  opt.local_edge_length = false;
  opt.seed = options.seed;
  MeshOptimizer optimizer(initial.positions, initial.faces, opt);
  NormalRenderer renderer(views.cameras);
  auto losses = [&](int, const std::vector<Vec3f>& positions, const std::vector<Vec3i>&,
                    const VertexNormals& normals, std::vector<Vec3f>& grad) {
    double loss = masked_image_l2(renderer, references, 4, 1.f);
    loss += background_alpha_l2(renderer, targets, 1.f);
    loss += expansion_loss(normals.unit, options.expansion_weight, grad);
    loss += out_of_box_loss(positions, options.out_of_box_limit, options.out_of_box_weight, grad);
    return loss;
  };
  run_optimisation_loop("coarse reconstruction", optimizer, renderer, options.steps, options.lr_decay, losses, report);
  if (report) report->seconds = timer.finish();
  return optimizer.mesh();
}

}  // namespace u3d
