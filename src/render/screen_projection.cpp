#include "render/screen_projection.h"

namespace u3d {

ScreenProjection project_to_screen(const std::vector<Vec3f>& positions, const Camera& camera) {
  ScreenProjection s;
  s.clip_from_world = camera.projection * camera.world_to_camera;
  s.width = float(camera.width);
  s.height = float(camera.height);
  s.orthographic = camera.orthographic;
  s.pixel.resize(positions.size());
  s.w.resize(positions.size());
  const Eigen::Matrix4f& m = s.clip_from_world;
  for (size_t i = 0; i < positions.size(); ++i) {
    Eigen::Vector4f c = m.block<4, 3>(0, 0) * positions[i] + m.col(3);
    s.pixel[i] = {(c.x() / c.w() + 1.f) * 0.5f * s.width, (1.f - c.y() / c.w()) * 0.5f * s.height};
    s.w[i] = c.w();
  }
  return s;
}

void ScreenGradient::reset(size_t vertex_count) {
  pixel.assign(vertex_count, Vec2f::Zero());
  w.assign(vertex_count, 0.f);
}

void add_world_gradient(const ScreenProjection& projection, const std::vector<Vec3f>& positions,
                        const ScreenGradient& screen, std::vector<Vec3f>& grad_positions) {
  const Eigen::Matrix4f& m = projection.clip_from_world;
  const Eigen::Matrix<float, 1, 3> rx = m.block<1, 3>(0, 0), ry = m.block<1, 3>(1, 0), rw = m.block<1, 3>(3, 0);
  for (size_t v = 0; v < positions.size(); ++v) {
    const Vec2f& gp = screen.pixel[v];
    const float gw = screen.w[v];
    if (gp.x() == 0.f && gp.y() == 0.f && gw == 0.f) continue;
    Eigen::Vector4f c = m.block<4, 3>(0, 0) * positions[v] + m.col(3);
    const float iw = 1.f / c.w();
    // pixel x = (cx/cw + 1) W/2, pixel y = (1 - cy/cw) H/2.
    Eigen::Matrix<float, 1, 3> jx = 0.5f * projection.width * iw * (rx - c.x() * iw * rw);
    Eigen::Matrix<float, 1, 3> jy = -0.5f * projection.height * iw * (ry - c.y() * iw * rw);
    grad_positions[v] += (gp.x() * jx + gp.y() * jy + gw * rw).transpose();
  }
}

}  // namespace u3d
