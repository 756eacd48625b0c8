#include "isomer/explicit_target.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "isomer/color_completion.h"
#include "render/rasterizer.h"

namespace u3d {
namespace {

// Bilinear RGBA sample at continuous pixel coordinates (pixel centres at +0.5), clamped at the border.
Vec4f sample_rgba(const Image& image, float px, float py) {
  const float x = std::clamp(px - 0.5f, 0.f, float(image.width - 1));
  const float y = std::clamp(py - 0.5f, 0.f, float(image.height - 1));
  const int x0 = int(x), y0 = int(y);  // x, y >= 0 after clamping
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const float fx = x - x0, fy = y - y0;
  Vec4f out;
  for (int c = 0; c < 4; ++c)
    out[c] = (1 - fy) * ((1 - fx) * image.at(x0, y0, c) + fx * image.at(x1, y0, c)) +
             fy * ((1 - fx) * image.at(x0, y1, c) + fx * image.at(x1, y1, c));
  return out;
}

// Binary alpha (>= 0.5) eroded by `radius` pixels (square structuring element). Rows in parallel: at
// 2048 px this is 4M pixels a view.
Image eroded_mask_copy(const Image& rgba, int radius) {
  Image out = rgba;
  const int w = rgba.width, h = rgba.height;
  const float* in = rgba.data.data();
  auto foreground = [&](int x, int y) { return is_foreground(in[(size_t(y) * w + x) * 4 + 3]); };
#pragma omp parallel for schedule(static)
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool keep = foreground(x, y);
      for (int dy = -radius; dy <= radius && keep; ++dy)
        for (int dx = -radius; dx <= radius && keep; ++dx) {
          const int xx = x + dx, yy = y + dy;
          keep = xx >= 0 && yy >= 0 && xx < w && yy < h && foreground(xx, yy);
        }
      out.data[(size_t(y) * w + x) * 4 + 3] = keep ? 1.f : 0.f;
    }
  return out;
}

}  // namespace

std::vector<uint8_t> visible_vertices(const Mesh& mesh, const std::vector<Vec3f>& face_normals, View v,
                                      const ColorTargetOptions& options) {
  const Camera cam = view_camera(v, options.raster_resolution);
  const RasterBuffer buf = rasterize(mesh, cam);
  std::vector<uint8_t> face_seen(mesh.faces.size(), 0);
  for (size_t p = 0; p < buf.pixel_count(); ++p)
    if (buf.covered(p)) face_seen[buf.face_id[p]] = 1;
  const Vec3f toward = cam.toward_camera();
  std::vector<uint8_t> seen(mesh.positions.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (face_seen[f] && face_normals[f].dot(toward) > options.facing_epsilon)
      for (int k = 0; k < 3; ++k) seen[mesh.faces[f][k]] = 1;
  return seen;
}

ExplicitTarget compute_explicit_target(const Mesh& mesh, const std::array<const Image*, 4>& images,
                                       const ColorTargetOptions& options) {
  require(options.raster_resolution >= 16, "ExplicitTarget: raster resolution must be at least 16");
  require(options.cos_power >= 0, "ExplicitTarget: cos power must not be negative");
  const size_t n = mesh.positions.size();
  const std::vector<Vec3f> fn = face_normals(mesh.positions, mesh.faces);
  const std::vector<Vec3f> vn = vertex_normals(mesh.positions, mesh.faces);
  ExplicitTarget target;
  target.weighted_sum.assign(n, Vec3f(0, 0, 0));
  target.weight.assign(n, 0.f);
  for (View v : kAllViews) {
    const Image& image = *images[size_t(v)];
    const float view_weight = options.view_weights[size_t(v)];
    if (view_weight <= 0.f) continue;
    require(image.channels == 4 && image.width > 1 && image.height > 1,
            std::string("ExplicitTarget: the ") + view_name(v) + " image must be RGBA");
    const std::vector<uint8_t> seen = visible_vertices(mesh, fn, v, options);
    const Camera cam = view_camera(v, image.width);
    const Vec3f toward = cam.toward_camera();
#pragma omp parallel for schedule(static)
    for (long long i = 0; i < (long long)n; ++i) {
      if (!seen[i]) continue;
      const Vec3f px = cam.to_pixel(mesh.positions[i]);
      if (px.x() < 0 || px.y() < 0 || px.x() > image.width || px.y() > image.height) continue;
      const Vec4f s = sample_rgba(image, px.x(), px.y());
      const float w = view_weight * std::pow(std::abs(vn[i].dot(toward)), float(options.cos_power)) *
                      std::clamp(s[3], 0.f, 1.f);
      target.weighted_sum[i] += w * s.head<3>().cwiseMax(0.f).cwiseMin(1.f);
      target.weight[i] += w;
    }
  }
  return target;
}

ColoringReport color_mesh(Mesh& mesh, const ViewSet& views, const ColoringOptions& options) {
  std::array<Image, 4> eroded;
  std::array<const Image*, 4> images;
  for (View v : kAllViews) {
    eroded[size_t(v)] = eroded_mask_copy(views[v].rgb, options.mask_erosion_px);
    images[size_t(v)] = &eroded[size_t(v)];
  }
  const ExplicitTarget target = compute_explicit_target(mesh, images, options.target);
  const float t = options.confidence_threshold;
  const size_t n = mesh.positions.size();
  mesh.colors.assign(n, options.fallback_color);
  std::vector<uint8_t> known(n, 0);
  ColoringReport report;
  for (size_t v = 0; v < n; ++v) {
    const float w = target.weight[v];
    if (w > t) {
      mesh.colors[v] = target.mean(v);
    } else if (t > 0) {  // official "smooth": fade from the fallback toward the few samples there are
      mesh.colors[v] = (options.fallback_color * (t - w) + target.weighted_sum[v]) / t;
    }
    known[v] = w >= t && w > 0;
    report.confident += known[v];
  }
  const ColorCompletionReport completion = complete_vertex_colors(mesh.faces, mesh.colors, known);
  report.completed = completion.filled;
  report.unreachable = completion.unreachable;
  for (Vec3f& c : mesh.colors) c = c.cwiseMax(0.f).cwiseMin(1.f);
  return report;
}

}  // namespace u3d
