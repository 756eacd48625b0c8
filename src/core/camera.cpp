#include "core/camera.h"

#include <Eigen/Geometry>
#include <cmath>

#include "core/error.h"

namespace u3d {

Eigen::Vector3f Camera::position() const {
  Eigen::Matrix3f r = rotation();
  return -r.transpose() * world_to_camera.topRightCorner<3, 1>();
}

Eigen::Vector3f Camera::toward_camera() const { return rotation().row(2).transpose(); }

Eigen::Vector4f Camera::to_clip(const Eigen::Vector3f& world) const {
  return projection * (world_to_camera * world.homogeneous());
}

Eigen::Vector3f Camera::to_pixel(const Eigen::Vector3f& world) const {
  Eigen::Vector4f cam = world_to_camera * world.homogeneous();
  Eigen::Vector4f clip = projection * cam;
  float xn = clip.x() / clip.w(), yn = clip.y() / clip.w();
  return {(xn + 1.f) * 0.5f * float(width), (1.f - yn) * 0.5f * float(height), -cam.z()};
}

Eigen::Matrix4f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up) {
  Eigen::Vector3f z = (eye - target).normalized();  // camera +z points toward the viewer
  Eigen::Vector3f up_used = up;
  if (std::abs(z.dot(up.normalized())) > 0.999f) up_used = Eigen::Vector3f(0, 0, -1);  // looking straight down/up
  Eigen::Vector3f x = up_used.cross(z).normalized();
  Eigen::Vector3f y = z.cross(x);
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<1, 3>(0, 0) = x.transpose();
  m.block<1, 3>(1, 0) = y.transpose();
  m.block<1, 3>(2, 0) = z.transpose();
  m(0, 3) = -x.dot(eye);
  m(1, 3) = -y.dot(eye);
  m(2, 3) = -z.dot(eye);
  return m;
}

Camera orthographic_camera(const Eigen::Vector3f& toward_camera, int width, int height, float half_extent,
                           float distance) {
  require(width > 0 && height > 0, "camera resolution must be positive");
  Camera c;
  c.width = width;
  c.height = height;
  c.orthographic = true;
  c.world_to_camera = look_at(toward_camera.normalized() * distance, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitY());
  float aspect = float(width) / float(height);
  float hx = half_extent * aspect, hy = half_extent;
  float n = 0.f, f = 2.f * distance;  // depth range covers everything within `distance` of the origin
  Eigen::Matrix4f p = Eigen::Matrix4f::Zero();
  p(0, 0) = 1.f / hx;
  p(1, 1) = 1.f / hy;
  p(2, 2) = -2.f / (f - n);
  p(2, 3) = -(f + n) / (f - n);
  p(3, 3) = 1.f;
  c.projection = p;
  return c;
}

Camera perspective_camera(const Eigen::Vector3f& eye, int width, int height, float fov_y_deg, float near_plane,
                          float far_plane) {
  require(width > 0 && height > 0, "camera resolution must be positive");
  Camera c;
  c.width = width;
  c.height = height;
  c.orthographic = false;
  c.world_to_camera = look_at(eye, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitY());
  float t = std::tan(0.5f * fov_y_deg * float(M_PI) / 180.f);
  float aspect = float(width) / float(height);
  Eigen::Matrix4f p = Eigen::Matrix4f::Zero();
  p(0, 0) = 1.f / (t * aspect);
  p(1, 1) = 1.f / t;
  p(2, 2) = -(far_plane + near_plane) / (far_plane - near_plane);
  p(2, 3) = -2.f * far_plane * near_plane / (far_plane - near_plane);
  p(3, 2) = -1.f;
  c.projection = p;
  return c;
}

const char* view_name(View v) {
  switch (v) {
    case View::Front: return "front";
    case View::Right: return "right";
    case View::Back: return "back";
    case View::Left: return "left";
  }
  return "?";
}

float view_azimuth_deg(View v) { return 90.f * float(int(v)); }

Eigen::Vector3f orbit_direction(float azimuth_deg, float elevation_deg) {
  float az = azimuth_deg * float(M_PI) / 180.f, el = elevation_deg * float(M_PI) / 180.f;
  return {std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el)};
}

Camera view_camera(View v, int resolution) {
  return orthographic_camera(orbit_direction(view_azimuth_deg(v), 0.f), resolution, resolution);
}

}  // namespace u3d
