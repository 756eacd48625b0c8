#pragma once
// Cameras and the four canonical views. Everything here follows docs/conventions.md:
//   world +Y up; camera space x right, y up, looking along -z (toward the scene), so +z points at
//   the viewer; clip space as OpenGL; pixel (0,0) is the top-left pixel and pixel centres sit at
//   integer + 0.5.
#include <Eigen/Core>
#include <array>
#include <string>

namespace u3d {

struct Camera {
  Eigen::Matrix4f world_to_camera = Eigen::Matrix4f::Identity();  // rigid transform
  Eigen::Matrix4f projection = Eigen::Matrix4f::Identity();       // camera space -> clip space
  int width = 0;
  int height = 0;
  bool orthographic = true;

  // Camera centre in world space (for orthographic cameras: a point on the axis, behind the near plane).
  Eigen::Vector3f position() const;
  // Unit world-space direction from the scene toward the camera (camera +z axis).
  Eigen::Vector3f toward_camera() const;
  // Rotation part of world_to_camera: maps world directions to camera directions.
  Eigen::Matrix3f rotation() const { return world_to_camera.topLeftCorner<3, 3>(); }
  // World point -> clip space (x, y, z, w).
  Eigen::Vector4f to_clip(const Eigen::Vector3f& world) const;
  // World point -> continuous pixel coordinates (x right, y down; pixel centres at +0.5) and
  // camera-space depth (distance in front of the camera along -z, positive for visible points).
  Eigen::Vector3f to_pixel(const Eigen::Vector3f& world) const;
};

// Camera at `eye` looking at `target`, with `up` as the approximate up direction.
Eigen::Matrix4f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up);

// Orthographic camera seeing [-half_extent, half_extent]^2 around its axis (square pixels when
// width == height), placed `distance` from the origin along `toward_camera`.
Camera orthographic_camera(const Eigen::Vector3f& toward_camera, int width, int height, float half_extent = 1.f,
                           float distance = 10.f);

// Perspective camera at `eye` looking at the origin with vertical field of view fov_y_deg.
Camera perspective_camera(const Eigen::Vector3f& eye, int width, int height, float fov_y_deg, float near_plane = 0.01f,
                          float far_plane = 100.f);

// The four views of Unique3D, in this fixed order everywhere (files, arrays, loops).
enum class View { Front = 0, Right = 1, Back = 2, Left = 3 };
inline constexpr std::array<View, 4> kAllViews = {View::Front, View::Right, View::Back, View::Left};
const char* view_name(View v);  // "front", "right", "back", "left"

// Azimuth of a view in degrees: front 0, right 90, back 180, left 270 (camera position
// (sin az cos el, sin el, cos az cos el)).
float view_azimuth_deg(View v);

// Unit direction toward the camera of a turntable position (degrees).
Eigen::Vector3f orbit_direction(float azimuth_deg, float elevation_deg);

// Orthographic camera of a canonical view covering [-1,1]^2 world units at resolution x resolution.
Camera view_camera(View v, int resolution);

// The space a normal map encodes its normals in: world space, or its view's camera space (x right,
// y up, z toward the camera).
enum class NormalSpace { World, Camera };

}  // namespace u3d
