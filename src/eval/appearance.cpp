#include "eval/appearance.h"

#include <algorithm>

#include "core/atomic_file.h"
#include "core/camera.h"
#include "core/error.h"
#include "eval/image_metrics.h"
#include "render/rasterizer.h"
#include "render/shade.h"
#include "render/supersample.h"

namespace u3d {

namespace {

float farthest_vertex(const Mesh& mesh) {
  float r = 0;
  for (const auto& p : mesh.positions) r = std::max(r, p.norm());
  return r;
}

Image render_colors(const Mesh& mesh, const Camera& camera, int ssaa) {
  Camera fine = camera;
  fine.width *= ssaa;
  fine.height *= ssaa;
  return composite_on_white(downsample_alpha_weighted(shade_colors(rasterize(mesh, fine), mesh), ssaa));
}

std::string view_tag(const TurntableView& v) {
  return "az" + std::to_string(int(v.azimuth_deg)) + "_el" + std::to_string(int(v.elevation_deg));
}

}  // namespace

std::vector<TurntableView> evaluation_views() {
  std::vector<TurntableView> views;
  for (float elevation : {0.f, 15.f, 30.f})
    for (int k = 0; k < 8; ++k) views.push_back({45.f * k, elevation});
  return views;
}

Image composite_on_white(const Image& rgba) {
  require(rgba.channels == 4, "composite_on_white needs an RGBA image");
  Image out(rgba.width, rgba.height, 3);
  for (size_t i = 0; i < rgba.pixel_count(); ++i) {
    float a = rgba.data[4 * i + 3];
    for (int c = 0; c < 3; ++c) out.data[3 * i + c] = a * rgba.data[4 * i + c] + (1 - a);
  }
  return out;
}

AppearanceMetrics appearance_metrics(const Mesh& pred, const Mesh& gt, const AppearanceOptions& options,
                                     const std::string& save_dir) {
  require(options.resolution >= 16, "render resolution must be at least 16, got " + std::to_string(options.resolution));
  require(options.ssaa >= 1 && options.ssaa <= 8, "ssaa must be between 1 and 8, got " + std::to_string(options.ssaa));
  pred.validate("predicted mesh");
  gt.validate("ground-truth mesh");
  AppearanceMetrics m;
  // 2% margin so silhouettes never touch the border; both renders share the framing.
  m.half_extent = 1.02f * std::max(farthest_vertex(pred), farthest_vertex(gt));
  require(m.half_extent > 0, "cannot frame meshes that are a single point at the origin");
  if (!save_dir.empty()) ensure_directory(save_dir);
  for (const TurntableView& v : evaluation_views()) {
    // The camera sits well outside both meshes; the orthographic depth range spans twice its distance.
    Camera camera = orthographic_camera(orbit_direction(v.azimuth_deg, v.elevation_deg), options.resolution,
                                        options.resolution, m.half_extent, 4.f * m.half_extent);
    Image a = render_colors(pred, camera, options.ssaa);
    Image b = render_colors(gt, camera, options.ssaa);
    m.views.push_back({v, psnr(a, b), ssim(a, b)});
    if (!save_dir.empty()) {
      save_image(a, std::filesystem::path(save_dir) / ("pred_" + view_tag(v) + ".png"));
      save_image(b, std::filesystem::path(save_dir) / ("gt_" + view_tag(v) + ".png"));
    }
  }
  for (const auto& s : m.views) {
    m.psnr += s.psnr / double(m.views.size());
    m.ssim += s.ssim / double(m.views.size());
  }
  return m;
}

}  // namespace u3d
