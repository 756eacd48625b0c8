#include "isomer/visual_hull.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/quadric_decimation.h"

namespace u3d {
namespace {

constexpr float kMaskThreshold = 0.5f;

// A view's alpha channel with its camera, read bilinearly between pixel centres (clamped at the
// image border).
struct MaskView {
  Camera camera;
  int width = 0, height = 0;
  std::vector<float> alpha;

  float sample(const Vec3f& world) const {
    const Vec3f pixel = camera.to_pixel(world);
    const float u = std::clamp(pixel.x() - 0.5f, 0.f, float(width - 1));
    const float v = std::clamp(pixel.y() - 0.5f, 0.f, float(height - 1));
    const int x0 = std::min(int(u), width - 2), y0 = std::min(int(v), height - 2);
    const float fx = u - float(x0), fy = v - float(y0);
    const float* row0 = alpha.data() + size_t(y0) * size_t(width) + size_t(x0);
    const float* row1 = row0 + width;
    return (1.f - fy) * ((1.f - fx) * row0[0] + fx * row0[1]) + fy * ((1.f - fx) * row1[0] + fx * row1[1]);
  }
};

MaskView mask_view(const ViewSet& views, View v, HullMasks source) {
  const Image& rgb = source == HullMasks::Rgb ? views[v].rgb : views[v].normals;
  require(rgb.channels == 4 && rgb.width >= 2 && rgb.height >= 2,
          std::string("visual hull: the ") + view_name(v) + " image has no usable alpha mask");
  MaskView m{view_camera(v, rgb.width), rgb.width, rgb.height, std::vector<float>(rgb.pixel_count())};
  bool any_inside = false;
  for (size_t p = 0; p < m.alpha.size(); ++p) {
    m.alpha[p] = rgb.data[p * 4 + 3];
    any_inside = any_inside || m.alpha[p] > kMaskThreshold;
  }
  require(any_inside, std::string("visual hull: the ") + view_name(v) + " mask is empty");
  return m;
}

}  // namespace

ScalarGrid visual_hull_field(const ViewSet& views, int resolution, HullMasks source) {
  require(resolution >= 4 && resolution <= 1024,
          "visual hull: resolution " + std::to_string(resolution) + " is outside [4, 1024]");
  std::vector<MaskView> masks;
  for (View v : kAllViews) masks.push_back(mask_view(views, v, source));

  const float voxel = 2.f / float(resolution);
  ScalarGrid grid;
  grid.nx = grid.ny = grid.nz = resolution + 2;
  grid.spacing = voxel;
  grid.origin = Vec3f::Constant(-1.f - 0.5f * voxel);  // sample 1 is the first voxel centre
  const float outside = -kMaskThreshold;
  grid.values.assign(size_t(grid.nx) * grid.ny * grid.nz, outside);
#pragma omp parallel for schedule(dynamic)
  for (int z = 1; z <= resolution; ++z)
    for (int y = 1; y <= resolution; ++y)
      for (int x = 1; x <= resolution; ++x) {
        const Vec3f centre = grid.position(x, y, z);
        float value = std::numeric_limits<float>::max();
        for (const MaskView& m : masks) {
          value = std::min(value, m.sample(centre) - kMaskThreshold);
          if (value <= outside) break;  // clear of this mask: no other view can change the minimum
        }
        grid.values[grid.index(x, y, z)] = value;
      }
  return grid;
}

Mesh carve_visual_hull(const ViewSet& views, const VisualHullOptions& options) {
  require(options.target_faces == 0 || options.target_faces >= 100,
          "visual hull: target face count must be 0 (keep all) or at least 100");
  StageTimer carve_timer("visual hull: carving " + std::to_string(options.resolution) + "^3 voxels");
  const ScalarGrid field = visual_hull_field(views, options.resolution);
  carve_timer.finish();
  StageTimer surface_timer("visual hull: extracting the surface");
  Mesh surface = extract_zero_surface(field);
  surface_timer.finish();
  require(!surface.faces.empty(), "visual hull: the four masks share no volume (no voxel is inside all of them)");
  if (options.target_faces == 0 || surface.face_count() <= size_t(options.target_faces)) return surface;
  StageTimer decimate_timer("visual hull: decimating " + std::to_string(surface.face_count()) + " faces");
  return decimate_closed_mesh(surface, size_t(options.target_faces));
}

}  // namespace u3d
