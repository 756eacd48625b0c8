#include "isomer/view_resolution.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace u3d {

ViewsAtResolution views_at_resolution(const std::vector<Image>& normal_maps, const std::vector<Camera>& cameras,
                                      int max_resolution) {
  require(normal_maps.size() == cameras.size(), "one normal map per camera");
  ViewsAtResolution out{normal_maps, cameras};
  if (max_resolution <= 0) return out;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const Image& map = normal_maps[i];
    require(map.channels == 4, "normal map must be RGBA (alpha = mask)");
    const int longer = std::max(map.width, map.height);
    if (longer <= max_resolution) continue;
    const float scale = float(max_resolution) / float(longer);
    const int w = std::max(1, int(std::lround(map.width * scale))), h = std::max(1, int(std::lround(map.height * scale)));
    Image premultiplied = map;
    for (size_t p = 0; p < premultiplied.pixel_count(); ++p)
      for (int c = 0; c < 3; ++c) premultiplied.data[p * 4 + c] *= premultiplied.data[p * 4 + 3];
    Image small = resize_image(premultiplied, w, h);
    for (size_t p = 0; p < small.pixel_count(); ++p) {
      const float a = small.data[p * 4 + 3];
      for (int c = 0; c < 3; ++c) small.data[p * 4 + c] = a > 1e-6f ? std::min(1.f, small.data[p * 4 + c] / a) : 0.f;
    }
    out.normal_maps[i] = std::move(small);
    // The projection maps to normalized device coordinates: only the pixel grid changes.
    out.cameras[i].width = w;
    out.cameras[i].height = h;
  }
  return out;
}

}  // namespace u3d
