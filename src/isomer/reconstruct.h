#pragma once
// ISOMER, the whole reconstruction from a view set to a coloured mesh, as a fixed sequence of stages
// (paper Sec. 3.2, official `geo_reconstruct`):
//   1. initial mesh            (initial_mesh.h)
//   2. [coarse and refine optimisation stages slot in here]
//   3. smooth and subdivide    (surface_cleanup.h)
//   4. colouring               (explicit_target.h: ExplicitTarget + completion)
//   5. output transform        (identity, or the official release's scale)
// Each stage is a function of the mesh so far; reconstruct() runs them in order and times each.
#include <string>
#include <vector>

#include "core/mesh.h"
#include "isomer/explicit_target.h"
#include "isomer/initial_mesh.h"
#include "isomer/surface_cleanup.h"
#include "isomer/view_set.h"

namespace u3d {

// The official app writes 0.675 * p (conventions.md 2.0: scale 1.35 / 2, no rotation).
inline constexpr float kOfficialOutputScale = 0.675f;

struct ReconstructOptions {
  InitialMeshOptions init;
  SurfaceCleanupOptions cleanup;
  ColouringOptions colouring;
  bool official_output_scale = false;  // false: the views' world frame, unscaled
};

struct StageTiming {
  std::string name;
  double seconds = 0.0;
};

struct ReconstructResult {
  Mesh mesh;
  std::vector<StageTiming> timings;
  ColouringReport colouring;
};

// The stages, in pipeline order.
Mesh stage_initial_mesh(const ViewSet& views, const ReconstructOptions& options);
Mesh stage_smooth_and_subdivide(const Mesh& mesh, const ReconstructOptions& options);
ColouringReport stage_colouring(Mesh& mesh, const ViewSet& views, const ReconstructOptions& options);
void stage_output_transform(Mesh& mesh, const ReconstructOptions& options);

ReconstructResult reconstruct(const ViewSet& views, const ReconstructOptions& options = {});

}  // namespace u3d
