#include "isomer/optimisation_loop.h"

#include <chrono>

#include "core/error.h"
#include "core/progress.h"

namespace u3d {

namespace {

// Adds the seconds since the last call to `into`.
class LapClock {
 public:
  void lap(double& into) {
    const auto now = std::chrono::steady_clock::now();
    into += std::chrono::duration<double>(now - last_).count();
    last_ = now;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace

NormalViews prepare_stage_views(const std::string& stage, const NormalViews& views, int render_resolution) {
  check_normal_views(views, stage);
  return at_resolution(views, render_resolution);
}

std::vector<NormalTarget> normal_targets(const NormalViews& views) {
  std::vector<NormalTarget> targets;
  for (const Image& map : views.normal_maps) targets.push_back(make_normal_target(map));
  return targets;
}

void run_optimisation_loop(const std::string& stage, MeshOptimizer& optimizer, NormalRenderer& renderer, int steps,
                           float lr_decay, const StageLosses& losses, StageReport* report) {
  StageProfile profile;
  std::vector<Vec3f> grad;
  double loss = 0.0;
  LapClock clock;
  for (int step = 0; step < steps; ++step) {
    optimizer.set_learning_rate(optimizer.learning_rate() * lr_decay);
    const std::vector<Vec3f>& positions = optimizer.positions();
    const std::vector<Vec3i>& faces = optimizer.faces();
    const VertexNormals normals = compute_vertex_normals(positions, faces);
    clock.lap(profile.step);
    renderer.render(positions, faces, optimizer.topology(), normals.unit);
    clock.lap(profile.render);
    grad.assign(positions.size(), Vec3f::Zero());
    loss = losses(step, positions, faces, normals, grad);
    clock.lap(profile.losses);
    renderer.backward(positions, faces, normals, grad);
    clock.lap(profile.backward);
    optimizer.step(grad);
    clock.lap(profile.step);
    optimizer.remesh();
    clock.lap(profile.remesh);
    progress_step(stage, step + 1, steps);
  }
  if (report) {
    report->steps = steps;
    report->final_loss = loss;
    report->final_edge_length = optimizer.mean_reference_edge_length();
    report->profile = profile;
  }
}

}  // namespace u3d
