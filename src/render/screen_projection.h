#pragma once
// World positions -> continuous pixel coordinates (x right, y down, centres at +0.5), and the way back
// for gradients: the differentiable primitives accumulate dL/d(pixel xy, clip w) per vertex in a
// ScreenGradient, and one pass turns it into dL/d(world position).
#include <Eigen/Core>
#include <vector>

#include "core/camera.h"
#include "core/mesh.h"

namespace u3d {

struct ScreenProjection {
  std::vector<Vec2f> pixel;  // per vertex
  std::vector<float> w;      // per vertex clip w (1 for orthographic cameras)
  Eigen::Matrix4f clip_from_world = Eigen::Matrix4f::Identity();
  float width = 0.f;
  float height = 0.f;
  bool orthographic = true;  // w == 1 everywhere: barycentrics are affine in the pixel position
};

ScreenProjection project_to_screen(const std::vector<Vec3f>& positions, const Camera& camera);

struct ScreenGradient {
  std::vector<Vec2f> pixel;  // dL/d(pixel x, y) per vertex
  std::vector<float> w;      // dL/d(clip w) per vertex

  void reset(size_t vertex_count);
};

// grad_positions[v] += d(pixel, w)/d(world)^T * screen gradient, for every vertex.
void add_world_gradient(const ScreenProjection& projection, const std::vector<Vec3f>& positions,
                        const ScreenGradient& screen, std::vector<Vec3f>& grad_positions);

}  // namespace u3d
