#pragma once
// Analytic view sets for the isomer tests: the four orthographic views of a sphere centred at the
// origin, rendered exactly (no rasterizer involved).
#include <cmath>
#include <functional>

#include "isomer/view_set.h"

namespace u3d::testing {

// colour(view, world normal) gives the RGB of a foreground pixel.
inline ViewSet sphere_views(float radius, int resolution,
                            const std::function<Vec3f(View, const Vec3f&)>& colour = nullptr) {
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
        const Vec3f col = colour ? colour(v, world) : Vec3f(0.8f, 0.5f, 0.2f);
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

}  // namespace u3d::testing
