#include "isomer/texture_bake.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "render/rasterizer.h"

namespace u3d {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Which atlas triangle covers each texel centre, and where: the atlas rasterized in UV space by the
// project's rasterizer (UV (0,0)..(1,1) mapped onto an orthographic view of [-1,1]^2, so texture row 0,
// the top, is v = 1 as the mesh UV convention wants).
RasterBuffer rasterize_atlas(const Mesh& atlas, int size) {
  std::vector<Vec3f> flat(atlas.uvs.size());
  for (size_t i = 0; i < flat.size(); ++i) flat[i] = Vec3f(2.f * atlas.uvs[i].x() - 1.f, 2.f * atlas.uvs[i].y() - 1.f, 0.f);
  return rasterize(flat, atlas.faces, orthographic_camera(Vec3f::UnitZ(), size, size));
}

// Texels not yet set take the mean of their set 8-neighbours, `rounds` times (all of a round at once).
void dilate(Image& texture, std::vector<uint8_t>& set, int rounds) {
  const int w = texture.width, h = texture.height;
  std::vector<uint8_t> next(set.size());
  for (int round = 0; round < rounds; ++round) {
    next = set;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (set[size_t(y) * w + x]) continue;
        Vec3f sum(0, 0, 0);
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= w || yy >= h || !set[size_t(yy) * w + xx]) continue;
            sum += Eigen::Map<const Vec3f>(texture.pixel(xx, yy));
            ++count;
          }
        if (!count) continue;
        Eigen::Map<Vec3f>(texture.pixel(x, y)) = sum / float(count);
        next[size_t(y) * w + x] = 1;
      }
    set.swap(next);
  }
}

}  // namespace

TextureBakeReport bake_texture(Mesh& mesh, const ViewSet& views, const ColoringOptions& coloring,
                               const TextureBakeOptions& options) {
  require(options.depth_tolerance_px >= 0.f, "texture baking: depth tolerance must not be negative");
  require(coloring.target.cos_power >= 0, "texture baking: cos power must not be negative");
  TextureBakeReport report;
  auto start = std::chrono::steady_clock::now();
  const UvAtlas atlas = axis_chart_atlas(mesh, options.atlas);
  report.uv_seconds = seconds_since(start);
  report.charts = atlas.chart_count;
  report.texel_efficiency = atlas.texel_efficiency;

  start = std::chrono::steady_clock::now();
  Mesh vertex_colored = mesh;
  report.vertices = color_mesh(vertex_colored, views, coloring);
  const std::vector<Vec3f> normals = vertex_normals(mesh.positions, mesh.faces);
  const std::vector<Vec3f> face_n = face_normals(mesh.positions, mesh.faces);

  const int size = options.atlas.texture_size;
  const RasterBuffer texels = rasterize_atlas(atlas.mesh, size);
  const size_t n = texels.pixel_count();
  std::vector<Vec3f> sum(n, Vec3f(0, 0, 0));
  std::vector<float> weight(n, 0.f);
  // The surface point and unit normal of a covered texel.
  auto surface = [&](size_t t, Vec3f& p, Vec3f& nrm, Vec3f* vertex_color) {
    const Vec3i& f = mesh.faces[texels.face_id[t]];
    const Vec2f b = texels.bary[t];
    const float b0 = 1.f - b.x() - b.y();
    p = b0 * mesh.positions[f[0]] + b.x() * mesh.positions[f[1]] + b.y() * mesh.positions[f[2]];
    nrm = b0 * normals[f[0]] + b.x() * normals[f[1]] + b.y() * normals[f[2]];
    nrm = nrm.squaredNorm() > 0.f ? Vec3f(nrm.normalized()) : face_n[texels.face_id[t]];
    if (vertex_color)
      *vertex_color = b0 * vertex_colored.colors[f[0]] + b.x() * vertex_colored.colors[f[1]] +
                      b.y() * vertex_colored.colors[f[2]];
  };
  const ColorTargetOptions& target = coloring.target;
  for (View v : kAllViews) {
    const float view_weight = target.view_weights[size_t(v)];
    if (view_weight <= 0.f) continue;
    const Image image = eroded_mask_copy(views[v].rgb, coloring.mask_erosion_px);
    const Camera cam = view_camera(v, image.width);
    const RasterBuffer depth = rasterize(mesh, cam);
    const Vec3f toward = cam.toward_camera();
    const float tolerance = options.depth_tolerance_px * 2.f / float(image.width);  // the view spans 2 units
#pragma omp parallel for schedule(dynamic, 16)
    for (int y = texels.footprint.y0; y <= texels.footprint.y1; ++y)
      for (int x = texels.footprint.x0; x <= texels.footprint.x1; ++x) {
        const size_t t = size_t(y) * size + x;
        if (!texels.covered(t) || face_n[texels.face_id[t]].dot(toward) <= target.facing_epsilon) continue;
        Vec3f p, nrm;
        surface(t, p, nrm, nullptr);
        const Vec3f px = cam.to_pixel(p);
        if (!(px.x() >= 0.f && px.y() >= 0.f && px.x() < float(image.width) && px.y() < float(image.height)))
          continue;
        const size_t pixel = size_t(int(px.y())) * depth.width + size_t(int(px.x()));
        if (depth.covered(pixel) && depth.face_id[pixel] != texels.face_id[t] &&
            px.z() > depth.depth[pixel] + tolerance)
          continue;  // hidden behind other surface
        const Vec4f s = sample_rgba(image, px.x(), px.y());
        const float w = view_weight * std::pow(std::abs(nrm.dot(toward)), float(target.cos_power)) *
                        std::clamp(s[3], 0.f, 1.f);
        sum[t] += w * s.head<3>().cwiseMax(0.f).cwiseMin(1.f);
        weight[t] += w;
      }
  }

  Image texture(size, size, 3, 0.f);
  std::vector<uint8_t> set(n, 0);
  const float threshold = coloring.confidence_threshold;
  Vec3f covered_sum(0, 0, 0);
  for (size_t t = 0; t < n; ++t) {
    if (!texels.covered(t)) continue;
    Vec3f color;
    if (weight[t] >= threshold && weight[t] > 0.f) {
      color = sum[t] / weight[t];
      ++report.texels_confident;
    } else {
      Vec3f p, nrm, vertex_color;
      surface(t, p, nrm, &vertex_color);
      color = threshold > 0.f ? Vec3f((sum[t] + (threshold - weight[t]) * vertex_color) / threshold) : vertex_color;
    }
    color = color.cwiseMax(0.f).cwiseMin(1.f);
    Eigen::Map<Vec3f>(texture.data.data() + t * 3) = color;
    covered_sum += color;
    set[t] = 1;
    ++report.texels_covered;
  }
  dilate(texture, set, options.atlas.gutter_texels + 2);
  const Vec3f mean = report.texels_covered ? Vec3f(covered_sum / float(report.texels_covered)) : Vec3f(0.5f, 0.5f, 0.5f);
  for (size_t t = 0; t < n; ++t)
    if (!set[t]) Eigen::Map<Vec3f>(texture.data.data() + t * 3) = mean;
  report.bake_seconds = seconds_since(start);

  Mesh out = atlas.mesh;
  out.colors.clear();
  out.face_material.clear();
  out.materials = {Material{"baked", Vec4f(1.f, 1.f, 1.f, 1.f), std::move(texture)}};
  mesh = std::move(out);
  return report;
}

}  // namespace u3d
