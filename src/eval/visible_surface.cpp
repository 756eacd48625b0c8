#include "eval/visible_surface.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "core/camera.h"
#include "core/error.h"
#include "render/rasterizer.h"

namespace u3d {

std::vector<Vec3f> sphere_directions(int count) {
  require(count > 0, "the number of view directions must be positive");
  std::vector<Vec3f> dirs;
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double y = 1.0 - (2.0 * i + 1.0) / double(count);  // cell centres: never +-1
    const double r = std::sqrt(1.0 - y * y), phi = golden_angle * i;
    dirs.emplace_back(float(r * std::cos(phi)), float(y), float(r * std::sin(phi)));
  }
  return dirs;
}

std::vector<uint8_t> visible_from_outside(const Mesh& mesh, const SurfaceSamples& samples,
                                          const VisibilityOptions& options) {
  require(!mesh.faces.empty(), "visibility needs a mesh with faces");
  require(options.resolution >= 16, "visibility resolution must be at least 16");
  require(samples.points.size() == samples.faces.size(), "every sample needs its face");
  // Centre the mesh on its bounding sphere so every view frames all of it.
  Eigen::AlignedBox3f box;
  for (const Vec3f& p : mesh.positions) box.extend(p);
  const Vec3f centre = box.center();
  float radius = 0;
  for (const Vec3f& p : mesh.positions) radius = std::max(radius, (p - centre).norm());
  radius = std::max(radius * 1.02f, 1e-6f);
  std::vector<Vec3f> positions(mesh.positions.size());
  for (size_t i = 0; i < positions.size(); ++i) positions[i] = mesh.positions[i] - centre;

  const float tolerance = 2.f * (2.f * radius / float(options.resolution));
  std::vector<uint8_t> visible(samples.points.size(), 0);
  RasterBuffer raster;
  for (const Vec3f& direction : sphere_directions(options.directions)) {
    const Camera camera =
        orthographic_camera(direction, options.resolution, options.resolution, radius, 2.f * radius + 1.f);
    rasterize_into(positions, mesh.faces, camera, raster);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < long(samples.points.size()); ++i) {
      if (visible[i]) continue;
      const Vec3f q = camera.to_pixel(samples.points[i] - centre);
      const int x = std::clamp(int(std::floor(q.x())), 0, raster.width - 1);
      const int y = std::clamp(int(std::floor(q.y())), 0, raster.height - 1);
      const size_t pixel = size_t(y) * size_t(raster.width) + size_t(x);
      // Depth alone decides: at grazing angles a pixel showing the sample's own face can show a part of
      // it far in front (a large face running under an occluder).
      if (raster.depth[pixel] >= q.z() - tolerance) visible[i] = 1;
    }
  }
  return visible;
}

}  // namespace u3d
