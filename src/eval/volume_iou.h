#pragma once
// Volume IoU on a regular occupancy grid. A grid cell is inside a mesh when the generalized winding
// number at its centre has magnitude >= 0.5: correct for closed meshes of either orientation and
// graceful for open, cracked or self-intersecting reconstructions (no ray casting, no voting).
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct VolumeIou {
  double iou = 0;  // |P ∩ G| / |P ∪ G| in cells; 0 when neither mesh encloses a cell
  int resolution = 0;
  size_t pred_cells = 0;
  size_t gt_cells = 0;
  size_t intersection_cells = 0;
  size_t union_cells = 0;
  Eigen::AlignedBox3f grid_box;  // union of both bounding boxes
};

// resolution^3 cells spanning the union of both meshes' bounding boxes (cells are boxes, not
// necessarily cubes; all cells have the same volume, so cell counts are volumes).
VolumeIou volume_iou(const Mesh& pred, const Mesh& gt, int resolution);

// Inside/outside (1/0) at the centres of resolution^3 cells spanning `box`, x fastest.
std::vector<uint8_t> occupancy_grid(const Mesh& mesh, const Eigen::AlignedBox3f& box, int resolution);

}  // namespace u3d
