#include "eval/input_view_psnr.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "eval/image_metrics.h"
#include "render/rasterizer.h"
#include "render/shade.h"
#include "render/supersample.h"

namespace u3d {

InputViewPsnr input_view_psnr(const Mesh& mesh, const ViewSet& views, int ssaa) {
  require(ssaa >= 1 && ssaa <= 8, "input-view PSNR: ssaa must be between 1 and 8, got " + std::to_string(ssaa));
  mesh.validate("predicted mesh");
  InputViewPsnr result;
  result.ssaa = ssaa;
  for (View v : kAllViews) {
    const Image& rgb = views[v].rgb;
    require(rgb.channels == 4 && rgb.width == rgb.height && !rgb.empty(),
            std::string("input-view PSNR: the ") + view_name(v) + " image must be square RGBA");
    Camera camera = view_camera(v, rgb.width);
    camera.width *= ssaa;
    camera.height *= ssaa;
    const Image render = downsample_alpha_weighted(shade_colors(rasterize(mesh, camera), mesh), ssaa);
    double sum = 0;
    size_t pixels = 0;
    for (size_t p = 0; p < rgb.pixel_count(); ++p) {
      if (!is_foreground(rgb.data[4 * p + 3]) || !is_foreground(render.data[4 * p + 3])) continue;
      ++pixels;
      for (int c = 0; c < 3; ++c) {
        const double d = double(render.data[4 * p + c]) - double(rgb.data[4 * p + c]);
        sum += d * d;
      }
    }
    const size_t k = size_t(v);
    result.pixels[k] = pixels;
    if (pixels == 0) continue;  // 0 dB
    const double mse = sum / (3.0 * double(pixels));
    result.views[k] = mse > 0 ? std::min(kPsnrCapDb, -10.0 * std::log10(mse)) : kPsnrCapDb;
    result.mean += result.views[k] / 4.0;
  }
  return result;
}

}  // namespace u3d
