#pragma once
// Appearance metrics: both meshes rendered with their own colours (vertex colours or textures, no
// lighting) from the same 24 turntable views, composited on white, compared with PSNR and SSIM.
#include <string>
#include <vector>

#include "core/image.h"
#include "core/mesh.h"

namespace u3d {

struct TurntableView {
  float azimuth_deg = 0;
  float elevation_deg = 0;
};

// Elevations 0, 15, 30 degrees x 8 azimuths 0, 45, ..., 315 (the Unique3D evaluation protocol).
std::vector<TurntableView> evaluation_views();

struct AppearanceOptions {
  int resolution = 256;  // output pixels per side
  int ssaa = 2;          // supersampling per axis, so silhouettes are anti-aliased alike in both renders
};

struct ViewScore {
  TurntableView view;
  double psnr = 0;
  double ssim = 0;
};

struct AppearanceMetrics {
  double psnr = 0;  // mean over views of the per-view PSNR (dB, capped at kPsnrCapDb)
  double ssim = 0;  // mean over views
  float half_extent = 0;  // orthographic half width of every view (world units)
  std::vector<ViewScore> views;
};

// Orthographic views looking at the origin, framing the sphere about the origin that holds both meshes.
// If `save_dir` is not empty, the white-composited renders are written there as
// pred_az<azimuth>_el<elevation>.png and gt_az<azimuth>_el<elevation>.png.
AppearanceMetrics appearance_metrics(const Mesh& pred, const Mesh& gt, const AppearanceOptions& options,
                                     const std::string& save_dir = "");

// RGBA (straight alpha) -> RGB over a white background.
Image composite_on_white(const Image& rgba);

}  // namespace u3d
