#include "eval/mask_agreement.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "geometry/grid_components.h"
#include "geometry/mesh_topology.h"
#include "render/rasterizer.h"

namespace u3d {
namespace {

// The pixels of `from` whose centre lies farther than `tolerance` from every pixel of `to`, grouped.
PixelBlobs beyond(const cv::Mat& from, const cv::Mat& to, float tolerance) {
  cv::Mat not_to;  // zero on `to`: the distance transform measures to its nearest zero
  cv::compare(to, 0, not_to, cv::CMP_EQ);
  cv::Mat distance;
  cv::distanceTransform(not_to, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat far = cv::Mat::zeros(from.size(), CV_8U);
  for (int y = 0; y < from.rows; ++y)
    for (int x = 0; x < from.cols; ++x)
      if (from.at<uint8_t>(y, x) && distance.at<float>(y, x) > tolerance) far.at<uint8_t>(y, x) = 1;
  PixelBlobs blobs;
  blobs.pixels = size_t(cv::countNonZero(far));
  if (blobs.pixels == 0) return blobs;
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(far, labels, stats, centroids, 8, CV_32S);
  blobs.blobs = size_t(count - 1);  // label 0 is the rest
  for (int i = 1; i < count; ++i)
    blobs.largest_blob = std::max(blobs.largest_blob, size_t(stats.at<int>(i, cv::CC_STAT_AREA)));
  return blobs;
}

}  // namespace

ViewMaskAgreement compare_coverage(const std::vector<uint8_t>& mesh_pixels, const std::vector<uint8_t>& mask_pixels,
                                   int width, int height, float tolerance_px) {
  require(width > 0 && height > 0 && mesh_pixels.size() == size_t(width) * size_t(height) &&
              mask_pixels.size() == mesh_pixels.size(),
          "mask agreement: the coverage images must have one size");
  // OpenCV reads the buffers in place; nothing writes to them.
  const cv::Mat mesh(height, width, CV_8U, const_cast<uint8_t*>(mesh_pixels.data()));
  const cv::Mat mask(height, width, CV_8U, const_cast<uint8_t*>(mask_pixels.data()));
  ViewMaskAgreement a;
  a.mesh_pixels = size_t(cv::countNonZero(mesh));
  a.mask_pixels = size_t(cv::countNonZero(mask));
  // With nothing to measure to, every pixel is beyond any tolerance.
  a.spurious = beyond(mesh, mask, a.mask_pixels ? tolerance_px : -1.f);
  a.missing = beyond(mask, mesh, a.mesh_pixels ? tolerance_px : -1.f);
  return a;
}

int visual_hull_components(const ViewSet& views, int resolution) {
  require(resolution >= 2 && resolution <= 1024,
          "mask agreement: hull resolution " + std::to_string(resolution) + " is outside [2, 1024]");
  const int n = resolution;
  const float voxel = 2.f / float(n);
  // Voxel centre (x, y, z) -> a view's pixel: the views are orthographic, so the projection is affine
  // and a step along a grid axis moves the pixel by a fixed amount.
  struct Projection {
    Vec3f origin, step[3];
    const Image* mask;
  };
  std::vector<Projection> projections;
  for (View v : kAllViews) {
    const Image& mask = views[v].normals;
    const Camera camera = view_camera(v, mask.width);
    const Vec3f first = Vec3f::Constant(-1.f + 0.5f * voxel);
    Projection p{camera.to_pixel(first), {}, &mask};
    for (int axis = 0; axis < 3; ++axis) p.step[axis] = camera.to_pixel(first + voxel * Vec3f::Unit(axis)) - p.origin;
    projections.push_back(p);
  }
  ScalarGrid grid;
  grid.nx = grid.ny = grid.nz = n;
  grid.spacing = voxel;
  grid.origin = Vec3f::Constant(-1.f + 0.5f * voxel);
  grid.values.assign(size_t(n) * n * n, -1.f);
#pragma omp parallel for schedule(static)
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        bool in = true;
        for (const Projection& p : projections) {
          const Vec3f pixel = p.origin + float(x) * p.step[0] + float(y) * p.step[1] + float(z) * p.step[2];
          const int px = int(std::floor(pixel.x())), py = int(std::floor(pixel.y()));
          in = px >= 0 && py >= 0 && px < p.mask->width && py < p.mask->height && is_foreground(p.mask->at(px, py, 3));
          if (!in) break;
        }
        if (in) grid.values[grid.index(x, y, z)] = 1.f;
      }
  return count_inside_components(grid);
}

MaskAgreement mask_agreement(const Mesh& mesh, const ViewSet& views, const MaskAgreementOptions& options) {
  require(options.tolerance_px >= 0.f, "mask agreement: the tolerance must not be negative");
  MaskAgreement report;
  report.options = options;
  for (View v : kAllViews) {
    const Image& mask = views[v].normals;
    const RasterBuffer raster = rasterize(mesh, view_camera(v, mask.width));
    std::vector<uint8_t> covered(raster.pixel_count()), foreground(mask.pixel_count());
    for (size_t p = 0; p < covered.size(); ++p) covered[p] = raster.covered(p);
    for (size_t p = 0; p < foreground.size(); ++p) foreground[p] = is_foreground(mask.data[p * 4 + 3]);
    report.views[size_t(v)] = compare_coverage(covered, foreground, mask.width, mask.height, options.tolerance_px);
  }
  report.mesh_components = surface_topology(mesh).components;
  report.hull_components = visual_hull_components(views, options.hull_resolution);
  return report;
}

}  // namespace u3d
