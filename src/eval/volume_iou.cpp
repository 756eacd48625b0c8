#include "eval/volume_iou.h"

#include <cmath>

#include "core/error.h"
#include "geometry/triangle_bvh.h"
#include "geometry/triangle_split.h"
#include "geometry/winding_number.h"

namespace u3d {

std::vector<uint8_t> occupancy_grid(const Mesh& mesh, const Eigen::AlignedBox3f& box, int resolution) {
  require(resolution >= 2, "occupancy grid resolution must be at least 2, got " + std::to_string(resolution));
  const Vec3f cell = box.sizes() / float(resolution);
  // Pieces no longer than two cells keep the hierarchy's clusters small near every cell centre.
  require(!mesh.faces.empty(), "occupancy grid of a mesh without faces");
  require((box.sizes().array() > 0).all(), "occupancy grid box must have a positive size along every axis");
  TriangleSoup pieces = split_long_triangles(mesh.positions, mesh.faces, 2.f * cell.maxCoeff());
  TriangleBvh bvh(pieces.positions, pieces.faces);
  WindingNumber winding(bvh);
  const long n = long(resolution) * resolution * resolution;
  std::vector<uint8_t> inside(n);
#pragma omp parallel for schedule(dynamic, 256)
  for (long i = 0; i < n; ++i) {
    long x = i % resolution, y = (i / resolution) % resolution, z = i / (long(resolution) * resolution);
    Vec3f centre = box.min() + cell.cwiseProduct(Vec3f(x + 0.5f, y + 0.5f, z + 0.5f));
    inside[i] = std::abs(winding(centre)) >= 0.5 ? 1 : 0;
  }
  return inside;
}

VolumeIou volume_iou(const Mesh& pred, const Mesh& gt, int resolution) {
  require(!pred.faces.empty(), "volume IoU: the predicted mesh has no faces");
  require(!gt.faces.empty(), "volume IoU: the ground-truth mesh has no faces");
  VolumeIou r;
  r.resolution = resolution;
  for (const auto& p : pred.positions) r.grid_box.extend(p);
  for (const auto& p : gt.positions) r.grid_box.extend(p);
  // A box flat in some axis encloses no volume; its cell centres would all lie on the surface.
  if ((r.grid_box.sizes().array() <= 0).any()) return r;
  std::vector<uint8_t> a = occupancy_grid(pred, r.grid_box, resolution);
  std::vector<uint8_t> b = occupancy_grid(gt, r.grid_box, resolution);
  for (size_t i = 0; i < a.size(); ++i) {
    r.pred_cells += a[i];
    r.gt_cells += b[i];
    r.intersection_cells += a[i] & b[i];
    r.union_cells += a[i] | b[i];
  }
  r.iou = r.union_cells > 0 ? double(r.intersection_cells) / double(r.union_cells) : 0.0;
  return r;
}

}  // namespace u3d
