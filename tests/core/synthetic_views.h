#pragma once
// Analytic view sets for the isomer tests: the four orthographic views of a sphere centred at the
// origin and of a union of axis-aligned boxes, rendered exactly (no rasterizer involved).
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.h"
#include "core/temp_dir.h"
#include "core/view_set.h"

namespace u3d::testing {

// colour(view, world normal) gives the RGB of a foreground pixel.
inline ViewSet sphere_views(float radius, int resolution,
                            const std::function<Vec3f(View, const Vec3f&)>& color = nullptr) {
  std::array<Image, 4> rgb, normal_maps;
  std::array<std::string, 4> rgb_names, normal_names;
  for (View v : kAllViews) {
    const size_t k = size_t(v);
    const Eigen::Matrix3f camera_to_world = view_camera(v, resolution).rotation().transpose();
    Image& c = rgb[k] = Image(resolution, resolution, 4, 0.f);
    Image& n = normal_maps[k] = Image(resolution, resolution, 4, 0.f);
    for (int y = 0; y < resolution; ++y)
      for (int x = 0; x < resolution; ++x) {
        const float cx = (x + 0.5f) * 2.f / resolution - 1.f, cy = 1.f - (y + 0.5f) * 2.f / resolution;
        const float r2 = cx * cx + cy * cy;
        if (r2 >= radius * radius) continue;
        const Vec3f world = camera_to_world * Vec3f(cx, cy, std::sqrt(radius * radius - r2)) / radius;
        const Vec3f col = color ? color(v, world) : Vec3f(0.8f, 0.5f, 0.2f);
        for (int i = 0; i < 3; ++i) {
          n.at(x, y, i) = 0.5f * (world[i] + 1.f);
          c.at(x, y, i) = col[i];
        }
        n.at(x, y, 3) = c.at(x, y, 3) = 1.f;
      }
    rgb_names[k] = view_file_name(v, false);
    normal_names[k] = view_file_name(v, true);
  }
  return make_view_set(rgb, normal_maps, NormalSpace::World, rgb_names, normal_names);
}

using Box = std::pair<Vec3f, Vec3f>;  // lo, hi corners

// The four exact views of a union of axis-aligned boxes: a pixel is foreground where the view's ray
// passes through a box (normals: the view direction, all that matters here is the masks).
inline ViewSet boxes_views(const std::vector<Box>& boxes, int resolution) {
  std::array<Image, 4> rgb, normal_maps;
  std::array<std::string, 4> rgb_names, normal_names;
  for (View v : kAllViews) {
    const size_t k = size_t(v);
    const Camera camera = view_camera(v, resolution);
    const Eigen::Matrix3f camera_to_world = camera.rotation().transpose();
    const Vec3f toward = camera.toward_camera();
    Image& c = rgb[k] = Image(resolution, resolution, 4, 0.f);
    Image& n = normal_maps[k] = Image(resolution, resolution, 4, 0.f);
    for (int y = 0; y < resolution; ++y)
      for (int x = 0; x < resolution; ++x) {
        const float cx = (x + 0.5f) * 2.f / resolution - 1.f, cy = 1.f - (y + 0.5f) * 2.f / resolution;
        const Vec3f on_plane = camera_to_world * Vec3f(cx, cy, 0.f);
        bool covered = false;
        for (const Box& b : boxes) {
          bool inside = true;
          for (int i = 0; i < 3; ++i)
            if (std::abs(toward[i]) < 0.5f) inside = inside && on_plane[i] > b.first[i] && on_plane[i] < b.second[i];
          covered = covered || inside;
        }
        if (!covered) continue;
        for (int i = 0; i < 3; ++i) {
          n.at(x, y, i) = 0.5f * (toward[i] + 1.f);
          c.at(x, y, i) = 0.5f;
        }
        n.at(x, y, 3) = c.at(x, y, 3) = 1.f;
      }
    rgb_names[k] = view_file_name(v, false);
    normal_names[k] = view_file_name(v, true);
  }
  return make_view_set(rgb, normal_maps, NormalSpace::World, rgb_names, normal_names);
}


// Writes a view set's images as the 8 PNG files of a VIEWS_DIR (normals re-encoded as (n+1)/2).
inline void write_view_set(const ViewSet& views, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  for (View v : kAllViews) {
    save_image(views[v].rgb, dir / view_file_name(v, false));
    Image encoded = views[v].normals;
    for (size_t p = 0; p < encoded.pixel_count(); ++p)
      for (int c = 0; c < 3; ++c) encoded.data[p * 4 + c] = 0.5f * (encoded.data[p * 4 + c] + 1.f);
    save_image(encoded, dir / view_file_name(v, true));
  }
}

}  // namespace u3d::testing
