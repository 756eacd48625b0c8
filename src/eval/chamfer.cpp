#include "eval/chamfer.h"

#include "core/error.h"
#include "geometry/surface_sampling.h"
#include "geometry/triangle_bvh.h"

namespace u3d {

namespace {

std::vector<float> distances_to_surface(const std::vector<Vec3f>& points, const TriangleBvh& surface) {
  std::vector<float> out(points.size());
#pragma omp parallel for schedule(dynamic, 1024)
  for (long i = 0; i < long(points.size()); ++i) out[i] = surface.closest_point(points[i]).distance;
  return out;
}

double mean(const std::vector<float>& v, bool squared) {
  double sum = 0;
  for (float x : v) sum += squared ? double(x) * x : double(x);
  return v.empty() ? 0.0 : sum / double(v.size());
}

}  // namespace

SurfaceDistances surface_distances(const Mesh& pred, const Mesh& gt, size_t samples, uint64_t seed) {
  TriangleBvh pred_bvh(pred.positions, pred.faces), gt_bvh(gt.positions, gt.faces);
  // Different seeds per side so two identical meshes are not trivially sampled at identical points.
  SurfaceSamples pred_samples = sample_surface(pred.positions, pred.faces, samples, seed);
  SurfaceSamples gt_samples = sample_surface(gt.positions, gt.faces, samples, seed + 1);
  // Braced initializers run in order: the GT samples are measured before they move into the result.
  return {distances_to_surface(pred_samples.points, gt_bvh), distances_to_surface(gt_samples.points, pred_bvh),
          std::move(gt_samples)};
}

SurfaceDistances keep_gt_samples(const SurfaceDistances& d, const std::vector<uint8_t>& keep) {
  require(keep.size() == d.gt_to_pred.size(), "one keep flag per GT sample is needed");
  SurfaceDistances out;
  out.pred_to_gt = d.pred_to_gt;
  for (size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    out.gt_to_pred.push_back(d.gt_to_pred[i]);
    if (!d.gt_samples.points.empty()) {
      out.gt_samples.points.push_back(d.gt_samples.points[i]);
      out.gt_samples.faces.push_back(d.gt_samples.faces[i]);
    }
  }
  return out;
}

ChamferDistance chamfer_distance(const SurfaceDistances& d) {
  ChamferDistance c;
  c.accuracy = mean(d.pred_to_gt, false);
  c.completeness = mean(d.gt_to_pred, false);
  c.chamfer_l1 = 0.5 * (c.accuracy + c.completeness);
  c.chamfer_l2 = 0.5 * (mean(d.pred_to_gt, true) + mean(d.gt_to_pred, true));
  return c;
}

}  // namespace u3d
