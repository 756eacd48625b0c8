#pragma once
// The step loop both ISOMER optimisation stages share: decay the learning rate, render the four views
// with the current vertex normals, let the stage add its losses and their direct gradients, back-
// propagate the images' gradients to the vertices, step and remesh. Every part is timed, so the
// benches can say where a stage's time goes.
#include <functional>
#include <string>
#include <vector>

#include "isomer/mesh_optimizer.h"
#include "core/camera.h"
#include "core/image.h"
#include "isomer/normal_renderer.h"
#include "isomer/reconstruction_losses.h"
#include "isomer/stage_report.h"

namespace u3d {

// A stage's views: the normal maps, checked against their cameras and brought to the render
// resolution, with their loss targets.
struct StageViewTargets {
  std::vector<Image> normal_maps;
  std::vector<Camera> cameras;
  std::vector<NormalTarget> targets;
};

// `stage` names the stage in error messages ("coarse stage").
StageViewTargets prepare_stage_views(const std::string& stage, const std::vector<Image>& normal_maps,
                                     const std::vector<Camera>& cameras, int render_resolution);

// Returns the step's loss; adds direct position gradients (regularizers) to `grad` and fills the
// renderer's grad_image on active pixels.
using StageLosses = std::function<double(int step, const std::vector<Vec3f>& positions,
                                         const std::vector<Vec3i>& faces, const VertexNormals& normals,
                                         std::vector<Vec3f>& grad)>;

// Runs `steps` steps; the learning rate is multiplied by lr_decay before each. Fills `report` (if
// given) except `seconds`.
void run_optimisation_loop(MeshOptimizer& optimizer, NormalRenderer& renderer, int steps, float lr_decay,
                           const StageLosses& losses, StageReport* report);

}  // namespace u3d
