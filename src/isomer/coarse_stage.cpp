#include "isomer/coarse_stage.h"

#include "core/error.h"
#include "core/progress.h"
#include "isomer/icosphere.h"
#include "isomer/mesh_optimizer.h"
#include "isomer/normal_renderer.h"
#include "isomer/reconstruction_losses.h"
#include "isomer/view_resolution.h"

namespace u3d {

CoarseStageOptions CoarseStageOptions::from_sphere() {
  CoarseStageOptions o;
  o.start_edge_length = 0.15f;
  o.end_edge_length = 0.01f;
  o.gain = 0.1f;
  return o;
}

StageMesh sphere_initial_mesh() {
  Mesh m = make_icosphere(3, 0.5f);
  return {m.positions, m.faces};
}

StageMesh run_coarse_stage(const StageMesh& initial, const std::vector<Image>& input_maps,
                           const std::vector<Camera>& input_cameras, const CoarseStageOptions& options,
                           StageReport* report) {
  require(!input_maps.empty() && input_maps.size() == input_cameras.size(), "coarse stage: one normal map per camera");
  for (size_t i = 0; i < input_cameras.size(); ++i)
    require(input_maps[i].width == input_cameras[i].width && input_maps[i].height == input_cameras[i].height,
            "coarse stage: normal map " + std::to_string(i) + " does not match its camera resolution");
  StageTimer timer("coarse reconstruction");
  const ViewsAtResolution views = views_at_resolution(input_maps, input_cameras, options.render_resolution);
  const std::vector<Image>& normal_maps = views.normal_maps;
  const std::vector<Camera>& cameras = views.cameras;
  std::vector<NormalTarget> targets;
  std::vector<const Image*> references;
  for (const Image& map : normal_maps) targets.push_back(make_normal_target(map));
  for (const NormalTarget& t : targets) references.push_back(&t.rgba);

  MeshOptimizerOptions opt;
  opt.learning_rate = options.learning_rate;
  opt.min_edge_length = options.end_edge_length;
  opt.max_edge_length = options.start_edge_length;
  opt.gain = options.gain;
  opt.local_edge_length = false;
  opt.seed = options.seed;
  MeshOptimizer optimizer(initial.positions, initial.faces, opt);
  NormalRenderer renderer(cameras);
  std::vector<Vec3f> grad;
  double loss = 0.0;
  for (int step = 0; step < options.steps; ++step) {
    optimizer.set_learning_rate(optimizer.learning_rate() * options.lr_decay);
    const std::vector<Vec3f>& positions = optimizer.positions();
    const std::vector<Vec3i>& faces = optimizer.faces();
    const VertexNormals normals = compute_vertex_normals(positions, faces);
    renderer.render(positions, faces, normals.unit);
    grad.assign(positions.size(), Vec3f::Zero());
    loss = masked_image_l2(renderer, references, 4, 1.f);
    loss += background_alpha_l2(renderer, targets, 1.f);
    loss += expansion_loss(normals.unit, options.expansion_weight, grad);
    loss += out_of_box_loss(positions, options.out_of_box_limit, options.out_of_box_weight, grad);
    renderer.backward(positions, faces, normals, grad);
    optimizer.step(grad);
    optimizer.remesh();
  }
  if (report) {
    report->steps = options.steps;
    report->seconds = timer.finish();
    report->final_loss = loss;
    report->final_edge_length = optimizer.mean_reference_edge_length();
  }
  return {optimizer.positions(), optimizer.faces()};
}

}  // namespace u3d
