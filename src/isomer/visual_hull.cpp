#include "isomer/visual_hull.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/quadric_decimation.h"

namespace u3d {
namespace {

// The field is kept in units of 0.5 per voxel and clamped to +-1 (two voxels): enough to place the
// surface between neighbouring samples (marching_tetrahedra.h), diagonals included.
constexpr float kFieldLimit = 1.f;

// A view's mask as a signed distance to its outline, in pixels (positive inside, is_foreground), with
// its camera, read bilinearly between pixel centres (clamped at the image border). Pixels next to
// the outline take alpha - 0.5, which places an anti-aliased edge inside its pixel; the others take
// the distance between pixel centres to the nearest pixel across the outline, less half a pixel.
// Unlike alpha itself, which is flat a pixel away from an edge, the distance stays linear, so grid
// samples two pixels apart still put the surface where the mask's edge is.
struct MaskView {
  Camera camera;
  int width = 0, height = 0;
  std::vector<float> distance;

  float sample(const Vec3f& world) const {
    const Vec3f pixel = camera.to_pixel(world);
    const float u = std::clamp(pixel.x() - 0.5f, 0.f, float(width - 1));
    const float v = std::clamp(pixel.y() - 0.5f, 0.f, float(height - 1));
    const int x0 = std::min(int(u), width - 2), y0 = std::min(int(v), height - 2);
    const float fx = u - float(x0), fy = v - float(y0);
    const float* row0 = distance.data() + size_t(y0) * size_t(width) + size_t(x0);
    const float* row1 = row0 + width;
    return (1.f - fy) * ((1.f - fx) * row0[0] + fx * row0[1]) + fy * ((1.f - fx) * row1[0] + fx * row1[1]);
  }
};

MaskView mask_view(const ViewSet& views, View v, HullMasks source) {
  const Image& rgb = source == HullMasks::Rgb ? views[v].rgb : views[v].normals;
  require(rgb.channels == 4 && rgb.width >= 2 && rgb.height >= 2,
          std::string("visual hull: the ") + view_name(v) + " image has no usable alpha mask");
  cv::Mat inside(rgb.height, rgb.width, CV_8U), outside(rgb.height, rgb.width, CV_8U);
  bool any_inside = false;
  for (int y = 0; y < rgb.height; ++y)
    for (int x = 0; x < rgb.width; ++x) {
      const bool in = is_foreground(rgb.at(x, y, 3));
      inside.at<uint8_t>(y, x) = in ? 255 : 0;
      outside.at<uint8_t>(y, x) = in ? 0 : 255;
      any_inside = any_inside || in;
    }
  require(any_inside, std::string("visual hull: the ") + view_name(v) + " mask is empty");
  // Distance of each pixel to the nearest pixel on the other side (0 on the own side's complement).
  cv::Mat to_outside, to_inside;
  cv::distanceTransform(inside, to_outside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(outside, to_inside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  MaskView m{view_camera(v, rgb.width), rgb.width, rgb.height, std::vector<float>(rgb.pixel_count())};
  for (int y = 0; y < rgb.height; ++y)
    for (int x = 0; x < rgb.width; ++x) {
      const bool in = inside.at<uint8_t>(y, x) != 0;
      const float across = in ? to_outside.at<float>(y, x) : to_inside.at<float>(y, x);
      const float alpha = rgb.at(x, y, 3);
      float d = across <= 1.f ? alpha - 0.5f : across - 0.5f;  // next to the outline: the edge within
      if (across <= 1.f) d = in ? std::max(d, 0.f) : std::min(d, 0.f);
      else if (!in) d = -d;
      m.distance[size_t(y) * size_t(rgb.width) + size_t(x)] = d;
    }
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
  // A world length in the field's units: pixels of the (square, [-1, 1]-wide) views to voxels.
  std::vector<float> to_field;
  for (const MaskView& m : masks) to_field.push_back(0.5f * (2.f / float(m.width)) / voxel);
  const float outside = -kFieldLimit;
  grid.values.assign(size_t(grid.nx) * grid.ny * grid.nz, outside);
#pragma omp parallel for schedule(dynamic)
  for (int z = 1; z <= resolution; ++z)
    for (int y = 1; y <= resolution; ++y)
      for (int x = 1; x <= resolution; ++x) {
        const Vec3f centre = grid.position(x, y, z);
        float value = kFieldLimit;
        for (size_t i = 0; i < masks.size(); ++i) {
          value = std::min(value, masks[i].sample(centre) * to_field[i]);
          if (value <= outside) break;  // far outside this mask: no other view can change the minimum
        }
        grid.values[grid.index(x, y, z)] = std::max(value, outside);
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
