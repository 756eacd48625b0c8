#pragma once
// Chamfer distance between two surfaces, estimated from dense uniform surface samples. Each sample's
// distance is measured to the other *surface* (exact closest point on its triangles), not to the other
// sample set: identical meshes then give 0 whatever the samples, and the result does not depend on
// how densely the other side was sampled.
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "geometry/surface_sampling.h"

namespace u3d {

struct SurfaceDistances {
  std::vector<float> pred_to_gt;  // per sample on the prediction: distance to the GT surface
  std::vector<float> gt_to_pred;  // per sample on the GT: distance to the predicted surface
  SurfaceSamples gt_samples;      // where gt_to_pred was measured
};

// `samples` points on each mesh (area-uniform, deterministic for a seed). Throws Error if a mesh
// has no faces or no area.
SurfaceDistances surface_distances(const Mesh& pred, const Mesh& gt, size_t samples, uint64_t seed);

struct ChamferDistance {
  double accuracy = 0;         // mean pred->GT distance
  double completeness = 0;     // mean GT->pred distance
  double chamfer_l1 = 0;       // (accuracy + completeness) / 2, unsquared distances
  double chamfer_l2 = 0;       // same with squared distances
};

ChamferDistance chamfer_distance(const SurfaceDistances& d);

// The same distances with only the GT samples whose `keep` flag is set (e.g. the visible ones).
SurfaceDistances keep_gt_samples(const SurfaceDistances& d, const std::vector<uint8_t>& keep);

}  // namespace u3d
