#pragma once
// Makes a nearly-closed surface closed and manifold. Open3D's Poisson output and its quadric
// decimation occasionally leave a few non-manifold edges or vertices and small holes; ISOMER needs a
// closed manifold. Faces at non-manifold edges/vertices are removed and every boundary loop is then
// closed by a fan around a new vertex at the loop's centroid. Faces end up oriented outward (each
// connected piece encloses a positive volume).
#include "core/mesh.h"

namespace u3d {

struct MeshRepairReport {
  size_t faces_removed = 0;
  size_t holes_filled = 0;
  bool closed_manifold = false;  // the result passes mesh_topology().closed_manifold()
};

MeshRepairReport repair_to_closed_manifold(Mesh& mesh, int max_passes = 8);

}  // namespace u3d
