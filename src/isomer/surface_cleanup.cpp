#include "isomer/surface_cleanup.h"

#include <algorithm>

#include <Eigen/Geometry>

#include "core/error.h"
#include "geometry/disjoint_sets.h"
#include "geometry/edge_topology.h"
#include "geometry/loop_subdivision.h"
#include "geometry/mesh_repair.h"
#include "geometry/mesh_topology.h"

namespace u3d {

void smooth_uniform_laplacian(Mesh& mesh, int iterations) {
  const size_t n = mesh.positions.size();
  const EdgeTopology topo = build_edge_topology(mesh.faces, n);  // rings in ascending order
  for (int it = 0; it < iterations; ++it) {
    std::vector<Vec3f> next = mesh.positions;
    for (size_t v = 0; v < n; ++v) {
      if (topo.degree(int(v)) == 0) continue;
      Vec3f sum = mesh.positions[v];
      for (int k = topo.ring_offsets[v]; k < topo.ring_offsets[v + 1]; ++k) sum += mesh.positions[topo.ring[k]];
      next[v] = sum / float(topo.degree(int(v)) + 1);
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

// Removes connected pieces (faces joined through shared vertices) with fewer than min_faces faces,
// never the largest piece.
void drop_crumbs(Mesh& mesh, int min_faces) {
  DisjointSets pieces(mesh.positions.size());
  for (const Vec3i& f : mesh.faces)
    for (int k = 1; k < 3; ++k) pieces.unite(f[k], f[0]);
  std::vector<size_t> piece_faces(mesh.positions.size(), 0);
  for (const Vec3i& f : mesh.faces) ++piece_faces[pieces.find(f[0])];
  const size_t largest = size_t(std::max_element(piece_faces.begin(), piece_faces.end()) - piece_faces.begin());
  std::erase_if(mesh.faces, [&](const Vec3i& f) {
    const size_t piece = size_t(pieces.find(f[0]));
    return piece != largest && piece_faces[piece] < size_t(std::max(min_faces, 0));
  });
  // Drop the vertices no face uses any more.
  std::vector<int> new_index(mesh.positions.size(), -1);
  for (const Vec3i& f : mesh.faces)
    for (int k = 0; k < 3; ++k) new_index[f[k]] = 0;
  std::vector<Vec3f> kept;
  for (size_t v = 0; v < new_index.size(); ++v)
    if (new_index[v] == 0) new_index[v] = int(kept.size()), kept.push_back(mesh.positions[v]);
  mesh.positions = std::move(kept);
  for (Vec3i& f : mesh.faces)
    for (int k = 0; k < 3; ++k) f[k] = new_index[f[k]];
}

}  // namespace

Mesh smooth_and_subdivide(const Mesh& input, const SurfaceCleanupOptions& options) {
  require(options.smooth_iterations >= 0 && options.subdivision_iterations >= 0,
          "surface clean-up: iteration counts must not be negative");
  Mesh smoothed = input;
  smoothed.colors.clear();
  smooth_uniform_laplacian(smoothed, options.smooth_iterations);

  // Loop subdivision needs a manifold (pymeshlab repairs non-manifold vertices and edges here too).
  // The optimisation stages already deliver one, outward: then the (Open3D, hash-map) repair is skipped.
  const MeshTopology topology = mesh_topology(smoothed);
  if (!topology.closed_manifold() || topology.volume <= 0.0) repair_to_closed_manifold(smoothed);
  drop_crumbs(smoothed, options.min_component_faces);
  Mesh mesh = std::move(smoothed);
  const BoundingBox box = bounding_box(mesh.positions);
  const double threshold = options.subdivision_threshold * double(box.extent().norm());
  for (int it = 0; it < options.subdivision_iterations && mean_edge_length(mesh) > threshold &&
                   mesh.faces.size() * 4 <= options.max_faces;
       ++it)
    mesh = loop_subdivide(mesh);
  return mesh;
}

}  // namespace u3d
