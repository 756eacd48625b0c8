#include "isomer/explicit_target_normals.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace u3d {

Vec4f sample_bilinear(const Image& image, float x, float y) {
  const float fx = std::clamp(x - 0.5f, 0.f, float(image.width - 1));
  const float fy = std::clamp(y - 0.5f, 0.f, float(image.height - 1));
  const int x0 = std::min(int(fx), image.width - 1), y0 = std::min(int(fy), image.height - 1);
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const float tx = fx - float(x0), ty = fy - float(y0);
  Vec4f out = Vec4f::Zero();
  const int ch = std::min(image.channels, 4);
  for (int c = 0; c < ch; ++c) {
    const float top = (1 - tx) * image.at(x0, y0, c) + tx * image.at(x1, y0, c);
    const float bottom = (1 - tx) * image.at(x0, y1, c) + tx * image.at(x1, y1, c);
    out[c] = (1 - ty) * top + ty * bottom;
  }
  if (ch < 4) out[3] = 1.f;
  return out;
}

ExplicitTargetNormals explicit_target_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                                           const std::vector<Vec3f>& vertex_normals,
                                           const std::vector<Image>& normal_maps, const std::vector<Camera>& cameras,
                                           const std::vector<const RasterBuffer*>& rasters,
                                           const ExplicitTargetOptions& options) {
  require(normal_maps.size() == cameras.size() && rasters.size() == cameras.size(),
          "explicit target: one normal map and raster per camera");
  require(options.view_weights.size() >= cameras.size(), "explicit target: one weight per view");
  const size_t n = positions.size();
  std::vector<Vec3f> color_sum(n, Vec3f::Zero());
  std::vector<float> weight_sum(n, 0.f);
  std::vector<float> square_sum(n, 0.f);  // sum of w |c|^2, for the spread of the views' samples
  std::vector<char> selected(n);
  std::vector<char> face_seen(faces.size());
  for (size_t view = 0; view < cameras.size(); ++view) {
    const Camera& cam = cameras[view];
    const Vec3f toward = cam.toward_camera();
    // Vertices of visible faces that face the camera.
    std::fill(face_seen.begin(), face_seen.end(), 0);
    for (int32_t f : rasters[view]->face_id)
      if (f >= 0) face_seen[f] = 1;
    std::fill(selected.begin(), selected.end(), 0);
    for (size_t f = 0; f < faces.size(); ++f) {
      if (!face_seen[f]) continue;
      const Vec3i& c = faces[f];
      const Vec3f normal = (positions[c[1]] - positions[c[0]]).cross(positions[c[2]] - positions[c[0]]).normalized();
      if (normal.dot(toward) > options.facing_epsilon) selected[c[0]] = selected[c[1]] = selected[c[2]] = 1;
    }
    const Image& map = normal_maps[view];
    for (size_t v = 0; v < n; ++v) {
      if (!selected[v]) continue;
      const Vec3f px = cam.to_pixel(positions[v]);
      if (px.x() < 0.f || px.y() < 0.f || px.x() > float(cam.width) || px.y() > float(cam.height)) continue;
      const Vec4f sample = sample_bilinear(map, px.x(), px.y());
      const float w = options.view_weights[view] * std::abs(vertex_normals[v].dot(toward)) * sample[3];
      color_sum[v] += w * sample.head<3>();
      weight_sum[v] += w;
      square_sum[v] += w * sample.head<3>().squaredNorm();
    }
  }
  ExplicitTargetNormals target{std::vector<Vec3f>(n), std::vector<float>(n, 0.f)};
  for (size_t v = 0; v < n; ++v) {
    if (weight_sum[v] <= options.confidence_threshold) {
      target.normals[v] = vertex_normals[v];
      continue;
    }
    const Vec3f mean = color_sum[v] / weight_sum[v];
    const Vec3f normal = mean * 2.f - Vec3f::Ones();
    target.normals[v] = normal.norm() > 1e-6f ? normal.normalized() : vertex_normals[v];
    // Weighted variance of the colours, E|c|^2 - |E c|^2; normals are 2c - 1, so twice the RMS.
    const float variance = std::max(square_sum[v] / weight_sum[v] - mean.squaredNorm(), 0.f);
    target.disagreement[v] = 2.f * std::sqrt(variance);
  }
  return target;
}

}  // namespace u3d
