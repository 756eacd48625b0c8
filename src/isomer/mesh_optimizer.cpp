#include "isomer/mesh_optimizer.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "isomer/remesh/spatial_order.h"

namespace u3d {

namespace {

// Passes between renumberings in space-filling-curve order (remesh/spatial_order.h). On the bundled
// example's refinement, every 10 passes took the rendering and back-propagation from 2.3-2.7 s and
// 1.2-1.4 s to 1.9-2.1 s and 0.8-0.9 s; every pass cost more in sorting (0.4 s) than it won, every 30
// won less.
constexpr int kSpatialOrderInterval = 10;

}  // namespace

MeshOptimizer::MeshOptimizer(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                             const MeshOptimizerOptions& options)
    : options_(options), faces_(faces), rng_(options.seed) {
  require(!positions.empty() && !faces.empty(), "mesh optimizer needs a non-empty mesh");
  require(options.min_edge_length > 0.f && options.min_edge_length <= options.max_edge_length,
          "edge length limits must satisfy 0 < min <= max");
  rows_.stride = kStride;
  rows_.values.assign(positions.size() * kStride, 0.f);
  for (size_t v = 0; v < positions.size(); ++v) {
    float* r = rows_.row(v);
    r[0] = positions[v].x(), r[1] = positions[v].y(), r[2] = positions[v].z();
    r[kRefLen] = options.max_edge_length;
  }
  refresh_positions();
}

void MeshOptimizer::refresh_positions() {
  positions_.resize(rows_.count());
  for (size_t v = 0; v < rows_.count(); ++v) positions_[v] = rows_.position(v);
}

Mesh MeshOptimizer::mesh() const {
  Mesh m;
  m.positions = positions_;
  m.faces = faces_;
  return m;
}

float MeshOptimizer::mean_reference_edge_length() const {
  double s = 0;
  for (size_t v = 0; v < rows_.count(); ++v) s += rows_.row(v)[kRefLen];
  return float(s / double(std::max<size_t>(rows_.count(), 1)));
}

void MeshOptimizer::step(const std::vector<Vec3f>& grad) {
  const size_t n = rows_.count();
  require(grad.size() == n, "gradient size does not match the vertex count");
  ++step_;
  constexpr float kEps = 1e-8f;
  // Neighbour means from the faces: on a closed manifold each neighbour appears in exactly two faces,
  // so counting per face corner weighs all neighbours equally.
  neighbor_sum_.assign(n, Vec3f::Zero());
  neighbor_count_.assign(n, 0.f);
  for (const Vec3i& f : faces_)
    for (int i = 0; i < 3; ++i) {
      neighbor_sum_[f[i]] += positions_[f[(i + 1) % 3]] + positions_[f[(i + 2) % 3]];
      neighbor_count_[f[i]] += 2.f;
    }
  // Bias-corrected exponential averages (Adam): new = a * old + b * x.
  auto weights = [&](float beta) {
    const float c_prev = 1.f - std::pow(beta, float(step_ - 1)), c = 1.f - std::pow(beta, float(step_));
    return std::pair<float, float>(beta * c_prev / c, (1.f - beta) / c);
  };
  const auto [a1, b1] = weights(options_.beta1);
  const auto [a2, b2] = weights(options_.beta2);
  const auto [an, bn] = options_.beta_speed > 0.f ? weights(options_.beta_speed) : std::pair<float, float>(0.f, 1.f);
  const float lr = options_.learning_rate *
                   std::min(1.f, float(step_) * (1.f - options_.beta1) / options_.ramp);
  double speed_sum = 0;
  for (size_t v = 0; v < n; ++v) {
    float* r = rows_.row(v);
    Vec3f g = grad[v];
    if (neighbor_count_[v] > 0.f) {
      const Vec3f laplace = positions_[v] - neighbor_sum_[v] / neighbor_count_[v];
      g += options_.laplacian_weight * r[kSpeed] * laplace;
    }
    for (int k = 0; k < 3; ++k) {
      if (step_ > 1) {
        const float lim = std::abs(r[kM1 + k]) * options_.grad_limit;
        g[k] = std::clamp(g[k], -lim, lim);
      }
      r[kM1 + k] = a1 * r[kM1 + k] + b1 * g[k];
    }
    r[kM2] = a2 * r[kM2] + b2 * g.squaredNorm();
    const float denom = std::sqrt(r[kM2]) + kEps;
    const Vec3f velocity(r[kM1] / denom, r[kM1 + 1] / denom, r[kM1 + 2] / denom);
    r[kSpeed] = an * r[kSpeed] + bn * velocity.norm();
    speed_sum += r[kSpeed];
    for (int k = 0; k < 3; ++k) r[k] -= lr * velocity[k] * r[kRefLen];
  }
  // Edge-length controller: fast-moving vertices get longer edges, settled ones shorter.
  const float mean_speed = float(speed_sum / double(std::max<size_t>(n, 1)));
  for (size_t v = 0; v < n; ++v) {
    float* r = rows_.row(v);
    const float speed = options_.local_edge_length ? r[kSpeed] : mean_speed;
    r[kRefLen] = std::clamp(r[kRefLen] * (1.f + (speed - options_.reference_speed) * options_.gain),
                            options_.min_edge_length, options_.max_edge_length);
  }
  refresh_positions();
}

RemeshCounts MeshOptimizer::remesh(bool flip) {
  const size_t n = rows_.count();
  std::vector<float> min_len(n), max_len(n);
  for (size_t v = 0; v < n; ++v) {
    min_len[v] = rows_.row(v)[kRefLen] * (1.f - options_.edge_length_tolerance);
    max_len[v] = rows_.row(v)[kRefLen] * (1.f + options_.edge_length_tolerance);
  }
  const RemeshCounts c =
      remesh_pass(rows_, faces_, std::move(min_len), std::move(max_len), flip, rng_, options_.max_vertices, &topology_);
  if (++remesh_passes_ % kSpatialOrderInterval == 0) {
    reorder_spatially(rows_, faces_);
    topology_.invalidate();
  }
  refresh_positions();
  return c;
}

}  // namespace u3d
