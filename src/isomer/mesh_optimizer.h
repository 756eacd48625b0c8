#pragma once
// The continuous-remeshing optimizer (Palfinger 2022; the official MeshOptimizer): Adam-like
// per-vertex moments with one scalar second moment per vertex, steps measured in units of a reference
// edge length, a Laplacian term scaled by each vertex's relative speed, and an edge-length controller
// that shrinks the reference length while vertices move slowly. After each step, remesh() collapses,
// splits and flips edges toward that length; the optimizer state rides along with the vertices.
#include <random>
#include <vector>

#include "core/mesh.h"
#include "isomer/remesh/remesh.h"
#include "isomer/remesh/vertex_rows.h"

namespace u3d {

struct MeshOptimizerOptions {
  float learning_rate = 0.3f;
  float beta1 = 0.8f;                 // first-moment decay (as Adam)
  float beta2 = 0.8f;                 // second-moment decay (as Adam)
  float beta_speed = 0.f;             // time smoothing of the relative speed; 0 = none
  float reference_speed = 0.3f;       // the controller's target relative speed (nu_ref)
  float min_edge_length = 0.01f;      // limits of the reference edge length
  float max_edge_length = 0.15f;      // (also its starting value)
  float edge_length_tolerance = 0.5f; // collapse below (1 - tol) * ref, split above (1 + tol) * ref
  float gain = 0.2f;                  // edge-length controller gain
  float laplacian_weight = 0.02f;
  float ramp = 1.f;                   // learning-rate warm-up; width ramp / (1 - beta1) steps
  float grad_limit = 10.f;            // gradients clipped to grad_limit * |first moment|
  bool local_edge_length = true;      // false: one global reference length from the mean speed
  size_t max_vertices = 1000000;
  unsigned seed = 1;                  // collapse edge choice
};

class MeshOptimizer {
 public:
  MeshOptimizer(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                const MeshOptimizerOptions& options = {});

  const std::vector<Vec3f>& positions() const { return positions_; }
  const std::vector<Vec3i>& faces() const { return faces_; }
  // The edge topology of faces(), shared with remeshing: a remesh() that flips leaves it up to date, and
  // one built here after a remesh() that did not is the one the next remesh() starts from.
  const EdgeTopology& topology() { return topology_.of(faces_, rows_.count()); }
  Mesh mesh() const;  // the current positions and faces
  float learning_rate() const { return options_.learning_rate; }
  void set_learning_rate(float lr) { options_.learning_rate = lr; }
  int steps_taken() const { return step_; }
  float mean_reference_edge_length() const;

  // One update from dL/d(positions) (sized like positions()).
  void step(const std::vector<Vec3f>& grad);
  // Remeshes toward the current reference lengths. Every 10th call also renumbers the vertices and
  // faces in Z-order (remesh/spatial_order.h), so vertex and face indices never outlive a remesh().
  RemeshCounts remesh(bool flip = true);

  // Row layout, exposed for tests of the state transport.
  static constexpr int kStride = 9;  // x y z | m1 (3) | m2 | speed | reference length
  static constexpr int kM1 = 3, kM2 = 6, kSpeed = 7, kRefLen = 8;
  const VertexRows& rows() const { return rows_; }

 private:
  void refresh_positions();

  MeshOptimizerOptions options_;
  VertexRows rows_;
  std::vector<Vec3i> faces_;
  std::vector<Vec3f> positions_;
  std::vector<Vec3f> neighbor_sum_;
  std::vector<float> neighbor_count_;
  std::mt19937 rng_;
  TopologyCache topology_;  // of faces_, kept between remeshing passes
  int step_ = 0;
  int remesh_passes_ = 0;   // remesh() calls, for the periodic renumbering
};

}  // namespace u3d
