#include "isomer/texture_bake.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>

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
  for (size_t i = 0; i < flat.size(); ++i)
    flat[i] = Vec3f(2.f * atlas.uvs[i].x() - 1.f, 2.f * atlas.uvs[i].y() - 1.f, 0.f);
  return rasterize(flat, atlas.faces, orthographic_camera(Vec3f::UnitZ(), size, size));
}

// The colour mask of a view as the vertex colouring uses it (explicit_target.h): alpha >= 0.5, eroded
// by `radius` pixels with a square element, pixels outside the image counting as background. Two
// separable passes, rows in parallel.
std::vector<uint8_t> eroded_mask(const Image& rgba, int radius) {
  const int w = rgba.width, h = rgba.height;
  std::vector<uint8_t> across(size_t(w) * h), out(size_t(w) * h);
#pragma omp parallel for schedule(static)
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool keep = true;
      for (int dx = -radius; dx <= radius && keep; ++dx)
        keep = x + dx >= 0 && x + dx < w && is_foreground(rgba.at(x + dx, y, 3));
      across[size_t(y) * w + x] = keep;
    }
#pragma omp parallel for schedule(static)
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool keep = true;
      for (int dy = -radius; dy <= radius && keep; ++dy)
        keep = y + dy >= 0 && y + dy < h && across[size_t(y + dy) * w + x];
      out[size_t(y) * w + x] = keep;
    }
  return out;
}

// RGB and mask of a view, bilinear at continuous pixel coordinates (pixel centres at +0.5), clamped
// at the border: the vertex colouring's sampling of its eroded RGBA copy.
Vec4f sample_view(const Image& image, const std::vector<uint8_t>& mask, float px, float py) {
  const float x = std::clamp(px - 0.5f, 0.f, float(image.width - 1));
  const float y = std::clamp(py - 0.5f, 0.f, float(image.height - 1));
  const int x0 = int(x), y0 = int(y);
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const float fx = x - x0, fy = y - y0;
  const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
  Vec4f out;
  for (int c = 0; c < 3; ++c)
    out[c] =
        w00 * image.at(x0, y0, c) + w10 * image.at(x1, y0, c) + w01 * image.at(x0, y1, c) + w11 * image.at(x1, y1, c);
  const size_t w = size_t(image.width);
  out[3] = w00 * mask[y0 * w + x0] + w10 * mask[y0 * w + x1] + w01 * mask[y1 * w + x0] + w11 * mask[y1 * w + x1];
  return out;
}

// Texels not yet set take the mean of their set 8-neighbours, `rounds` times (all of a round at once).
// Only the texels next to the set region are visited.
void dilate(Image& texture, std::vector<uint8_t>& set, int rounds) {
  const int w = texture.width, h = texture.height;
  auto for_neighbours = [&](int t, auto&& visit) {
    const int x = t % w, y = t / w;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if ((dx || dy) && x + dx >= 0 && y + dy >= 0 && x + dx < w && y + dy < h) visit((y + dy) * w + x + dx);
  };
  std::vector<uint8_t> queued(set.size(), 0);
  std::vector<int> frontier;
  for (int t = 0; t < w * h; ++t)
    if (!set[t]) {
      bool next_to_set = false;
      for_neighbours(t, [&](int n) { next_to_set = next_to_set || set[n]; });
      if (next_to_set) frontier.push_back(t), queued[t] = 1;
    }
  for (int round = 0; round < rounds && !frontier.empty(); ++round) {
    std::vector<Vec3f> values(frontier.size());
#pragma omp parallel for schedule(static)
    for (long long i = 0; i < (long long)frontier.size(); ++i) {
      Vec3f sum(0, 0, 0);
      int count = 0;
      for_neighbours(frontier[i], [&](int n) {
        if (set[n]) sum += Eigen::Map<const Vec3f>(texture.data.data() + size_t(n) * 3), ++count;
      });
      values[i] = sum / float(count);
    }
    for (size_t i = 0; i < frontier.size(); ++i) {
      Eigen::Map<Vec3f>(texture.data.data() + size_t(frontier[i]) * 3) = values[i];
      set[frontier[i]] = 1;
    }
    std::vector<int> next;
    for (int t : frontier)
      for_neighbours(t, [&](int n) {
        if (!set[n] && !queued[n]) next.push_back(n), queued[n] = 1;
      });
    frontier.swap(next);
  }
}

}  // namespace

TextureBakeReport bake_texture(Mesh& mesh, const ViewSet& views, const ColoringOptions& coloring,
                               const TextureBakeOptions& options) {
  require(options.depth_tolerance_px >= 0.f, "texture baking: depth tolerance must not be negative");
  const ColorTargetOptions& target = coloring.target;
  require(target.cos_power >= 0, "texture baking: cos power must not be negative");
  require(target.raster_resolution >= 16, "texture baking: raster resolution must be at least 16");
  TextureBakeReport report;
  const auto start = std::chrono::steady_clock::now();
  // The atlas (one thread: about 0.3 s for 40k faces) and what baking needs of the mesh alone, side by
  // side: neither reads the other's results, so both are the same as one after the other.
  UvAtlas atlas;
  Mesh vertex_colored = mesh;
  struct Sampled {  // a view as the texels sample it
    const Image* image;
    std::vector<uint8_t> mask;
    Camera cam;
    Vec3f toward;
    RasterBuffer depth;
    float view_weight;
  };
  std::vector<Sampled> sampled;
  std::exception_ptr failures[2];
#pragma omp parallel sections
  {
#pragma omp section
    try {
      atlas = axis_chart_atlas(mesh, options.atlas);
      report.uv_seconds = seconds_since(start);
    } catch (...) {
      failures[0] = std::current_exception();
    }
#pragma omp section
    try {
      // The vertex colouring, from the views at the visibility raster's resolution (it only fills what
      // the views barely see; at 2048 px it would cost more than the texels), reduced with alpha weights
      // so the background's colour does not bleed into the rim's vertices.
      ViewSet reduced;
      for (View v : kAllViews) {
        const Image& rgb = views[v].rgb;
        require(rgb.channels == 4 && rgb.width > 1 && rgb.height > 1,
                std::string("texture baking: the ") + view_name(v) + " image must be RGBA");
        const int r = std::min(rgb.width, target.raster_resolution);
        reduced[v].rgb = r < rgb.width ? resize_premultiplied(rgb, r, r) : rgb;
      }
      report.vertices = color_mesh(vertex_colored, reduced, coloring);
      for (View v : kAllViews) {
        const float view_weight = target.view_weights[size_t(v)];
        if (view_weight <= 0.f) continue;
        const Image& image = views[v].rgb;
        const Camera cam = view_camera(v, image.width);
        sampled.push_back({&image, eroded_mask(image, coloring.mask_erosion_px), cam, cam.toward_camera(),
                           rasterize(mesh, view_camera(v, target.raster_resolution)), view_weight});
      }
    } catch (...) {
      failures[1] = std::current_exception();
    }
  }
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
  report.charts = atlas.chart_count;

  // Each covered texel in one pass: its surface point and unit normal (interpolated vertex normals),
  // ExplicitTarget over the views, and its colour: the weighted mean, fading below the threshold
  // toward the vertex colouring.
  const int size = options.atlas.texture_size;
  const RasterBuffer texels = rasterize_atlas(atlas.mesh, size);
  std::vector<int32_t> covered;
  const PixelRect& rect = texels.footprint;
  if (!rect.empty()) covered.reserve(size_t(rect.x1 - rect.x0 + 1) * size_t(rect.y1 - rect.y0 + 1));  // no regrowth
  for (int y = texels.footprint.y0; y <= texels.footprint.y1; ++y)
    for (int x = texels.footprint.x0; x <= texels.footprint.x1; ++x)
      if (texels.covered(size_t(y) * size + x)) covered.push_back(y * size + x);
  const size_t count = covered.size();
  const std::vector<Vec3f> normals = vertex_normals(mesh.positions, mesh.faces);
  const std::vector<Vec3f> face_n = face_normals(mesh.positions, mesh.faces);
  const float tolerance =
      options.depth_tolerance_px * 2.f / float(target.raster_resolution);  // the view spans 2 units
  Image texture(size, size, 3, 0.f);
  std::vector<uint8_t> set(texels.pixel_count(), 0);
  const float threshold = coloring.confidence_threshold;
  size_t confident = 0;
#pragma omp parallel for schedule(static) reduction(+ : confident)
  for (long long i = 0; i < (long long)count; ++i) {
    const int face = texels.face_id[covered[i]];
    const Vec3i& f = mesh.faces[face];
    const Vec2f b = texels.bary[covered[i]];
    const float b0 = 1.f - b.x() - b.y();
    const Vec3f point = b0 * mesh.positions[f[0]] + b.x() * mesh.positions[f[1]] + b.y() * mesh.positions[f[2]];
    const Vec3f n = b0 * normals[f[0]] + b.x() * normals[f[1]] + b.y() * normals[f[2]];
    const Vec3f texel_normal = n.squaredNorm() > 0.f ? Vec3f(n.normalized()) : face_n[face];
    const Vec3f fallback =
        b0 * vertex_colored.colors[f[0]] + b.x() * vertex_colored.colors[f[1]] + b.y() * vertex_colored.colors[f[2]];
    Vec3f sum(0, 0, 0);
    float weight = 0.f;
    for (const Sampled& view : sampled) {
      const Image& image = *view.image;
      const RasterBuffer& depth = view.depth;
      const Vec3f& toward = view.toward;
      if (face_n[face].dot(toward) <= target.facing_epsilon) continue;
      const Vec3f px = view.cam.to_pixel(point);
      if (!(px.x() >= 0.f && px.y() >= 0.f && px.x() < float(image.width) && px.y() < float(image.height))) continue;
      const float to_raster = float(target.raster_resolution) / float(image.width);
      const int rx = std::min(int(px.x() * to_raster), depth.width - 1),
                ry = std::min(int(px.y() * to_raster), depth.height - 1);
      const size_t pixel = size_t(ry) * depth.width + rx;
      if (depth.covered(pixel) && depth.face_id[pixel] != face && px.z() > depth.depth[pixel] + tolerance)
        continue;  // hidden behind other surface
      const Vec4f s = sample_view(image, view.mask, px.x(), px.y());
      float w = view.view_weight * s[3];
      const float c = std::abs(texel_normal.dot(toward));
      for (int k = 0; k < target.cos_power; ++k) w *= c;
      sum += w * s.head<3>().cwiseMax(0.f).cwiseMin(1.f);
      weight += w;
    }
    Vec3f color;
    if (weight >= threshold && weight > 0.f) {
      color = sum / weight;
      ++confident;
    } else {
      color = threshold > 0.f ? Vec3f((sum + (threshold - weight) * fallback) / threshold) : fallback;
    }
    Eigen::Map<Vec3f>(texture.data.data() + size_t(covered[i]) * 3) = color.cwiseMax(0.f).cwiseMin(1.f);
    set[covered[i]] = 1;
  }
  report.texels_covered = count;
  report.texel_efficiency = float(double(count) / double(texels.pixel_count()));
  report.texels_confident = confident;
  Eigen::Vector3d total(0, 0, 0);
  for (int32_t t : covered) total += Eigen::Map<const Vec3f>(texture.data.data() + size_t(t) * 3).cast<double>();
  dilate(texture, set, options.atlas.gutter_texels + 2);
  const Vec3f mean = count ? Vec3f((total / double(count)).cast<float>()) : Vec3f(0.5f, 0.5f, 0.5f);
  for (size_t t = 0; t < set.size(); ++t)
    if (!set[t]) Eigen::Map<Vec3f>(texture.data.data() + t * 3) = mean;
  report.bake_seconds = seconds_since(start) - report.uv_seconds;

  Mesh out = atlas.mesh;
  out.colors.clear();
  out.face_material.clear();
  out.materials = {Material{"baked", Vec4f(1.f, 1.f, 1.f, 1.f), std::move(texture)}};
  mesh = std::move(out);
  return report;
}

}  // namespace u3d
