#include "isomer/view_resolution.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace u3d {

ViewsAtResolution views_at_resolution(const std::vector<Image>& normal_maps, const std::vector<Camera>& cameras,
                                      int max_resolution) {
  require(normal_maps.size() == cameras.size(), "one normal map per camera");
  for (const Image& map : normal_maps) require(map.channels == 4, "normal map must be RGBA (alpha = mask)");
  ViewsAtResolution out{std::vector<Image>(normal_maps.size()), cameras};
  const int count = int(normal_maps.size());
  // The views are independent; at 2048 px each one is 4M pixels of work.
#pragma omp parallel for schedule(dynamic, 1) if (count > 1)
  for (int i = 0; i < count; ++i) {
    const Image& map = normal_maps[size_t(i)];
    const int longer = std::max(map.width, map.height);
    if (max_resolution <= 0 || longer <= max_resolution) {
      out.normal_maps[size_t(i)] = map;
      continue;
    }
    const float scale = float(max_resolution) / float(longer);
    const int w = std::max(1, int(std::lround(map.width * scale))), h = std::max(1, int(std::lround(map.height * scale)));
    Image premultiplied(map.width, map.height, 4);
    for (size_t p = 0; p < map.pixel_count(); ++p) {
      const float* in = map.data.data() + p * 4;
      float* px = premultiplied.data.data() + p * 4;
      for (int c = 0; c < 3; ++c) px[c] = in[c] * in[3];
      px[3] = in[3];
    }
    Image small = resize_image(premultiplied, w, h);
    for (size_t p = 0; p < small.pixel_count(); ++p) {
      const float a = small.data[p * 4 + 3];
      for (int c = 0; c < 3; ++c) small.data[p * 4 + c] = a > 1e-6f ? std::min(1.f, small.data[p * 4 + c] / a) : 0.f;
    }
    out.normal_maps[size_t(i)] = std::move(small);
    // The projection maps to normalized device coordinates: only the pixel grid changes.
    out.cameras[size_t(i)].width = w;
    out.cameras[size_t(i)].height = h;
  }
  return out;
}

}  // namespace u3d
