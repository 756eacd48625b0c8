#pragma once
// The step loop both ISOMER optimisation stages share: decay the learning rate, render the four views
// with the current vertex normals, let the stage add its losses and their direct gradients, back-
// propagate the images' gradients to the vertices, step and remesh. Every part is timed, so the
// benches can say where a stage's time goes.
#include <functional>
#include <string>
#include <vector>

#include "isomer/mesh_optimizer.h"
#include "isomer/normal_renderer.h"
#include "isomer/normal_views.h"
#include "isomer/reconstruction_losses.h"
#include "isomer/stage_report.h"

namespace u3d {

// A stage's views, checked and brought to its render resolution; `stage` names the stage in error
// messages ("coarse stage").
NormalViews prepare_stage_views(const std::string& stage, const NormalViews& views, int render_resolution);

// The loss target of each view.
std::vector<NormalTarget> normal_targets(const NormalViews& views);

// Returns the step's loss; adds direct position gradients (regularizers) to `grad` and fills the
// renderer's grad_image on active pixels.
using StageLosses = std::function<double(int step, const std::vector<Vec3f>& positions,
                                         const std::vector<Vec3i>& faces, const VertexNormals& normals,
                                         std::vector<Vec3f>& grad)>;

// Runs `steps` steps; the learning rate is multiplied by lr_decay before each. Each step is reported as
// progress of `stage` (and may be cancelled there). Fills `report` (if given) except `seconds`.
void run_optimisation_loop(const std::string& stage, MeshOptimizer& optimizer, NormalRenderer& renderer, int steps,
                           float lr_decay, const StageLosses& losses, StageReport* report);

}  // namespace u3d
