#include "isomer/surface_cleanup.h"

#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>

#include "core/error.h"
#include "isomer/loop_subdivision.h"
#include "isomer/mesh_repair.h"
#include "isomer/open3d_bridge.h"

namespace u3d {

void smooth_uniform_laplacian(Mesh& mesh, int iterations) {
  const size_t n = mesh.positions.size();
  std::vector<std::vector<int>> neighbours(n);
  for (const Vec3i& f : mesh.faces)
    for (int k = 0; k < 3; ++k) {
      neighbours[f[k]].push_back(f[(k + 1) % 3]);
      neighbours[f[(k + 1) % 3]].push_back(f[k]);
    }
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  for (int it = 0; it < iterations; ++it) {
    std::vector<Vec3f> next = mesh.positions;
    for (size_t v = 0; v < n; ++v) {
      if (neighbours[v].empty()) continue;
      Vec3f sum = mesh.positions[v];
      for (int nb : neighbours[v]) sum += mesh.positions[nb];
      next[v] = sum / float(neighbours[v].size() + 1);
    }
    mesh.positions = std::move(next);
  }
}

namespace {

double mean_edge_length(const Mesh& mesh) {
  double total = 0;
  size_t count = 0;
  for (const Vec3i& f : mesh.faces)
    for (int k = 0; k < 3; ++k, ++count) total += (mesh.positions[f[k]] - mesh.positions[f[(k + 1) % 3]]).norm();
  return count ? total / double(count) : 0.0;
}

// Removes connected pieces with fewer than min_faces faces, never the largest piece.
void drop_crumbs(open3d::geometry::TriangleMesh& mesh, int min_faces) {
  auto [cluster, cluster_faces, cluster_area] = mesh.ClusterConnectedTriangles();
  if (cluster_faces.empty()) return;
  const size_t largest = size_t(std::max_element(cluster_faces.begin(), cluster_faces.end()) - cluster_faces.begin());
  std::vector<bool> drop(mesh.triangles_.size(), false);
  for (size_t f = 0; f < drop.size(); ++f)
    drop[f] = size_t(cluster[f]) != largest && cluster_faces[cluster[f]] < size_t(std::max(min_faces, 0));
  mesh.RemoveTrianglesByMask(drop);
  mesh.RemoveUnreferencedVertices();
}

}  // namespace

Mesh smooth_and_subdivide(const Mesh& input, const SurfaceCleanupOptions& options) {
  require(options.smooth_iterations >= 0 && options.subdivision_iterations >= 0,
          "surface clean-up: iteration counts must not be negative");
  Mesh smoothed = input;
  smoothed.colors.clear();
  smooth_uniform_laplacian(smoothed, options.smooth_iterations);

  // Loop subdivision needs a manifold (pymeshlab repairs non-manifold vertices and edges here too).
  repair_to_closed_manifold(smoothed);
  auto o3d = to_open3d(smoothed);
  drop_crumbs(*o3d, options.min_component_faces);
  Mesh mesh = from_open3d(*o3d);
  const BoundingBox box = bounding_box(mesh.positions);
  const double threshold = options.subdivision_threshold * double(box.extent().norm());
  for (int it = 0; it < options.subdivision_iterations && mean_edge_length(mesh) > threshold &&
                   mesh.faces.size() * 4 <= options.max_faces;
       ++it)
    mesh = loop_subdivide(mesh);
  return mesh;
}

}  // namespace u3d
