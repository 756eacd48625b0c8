#include "isomer/normal_views.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace u3d {

NormalViews normal_views(const ViewSet& views) {
  NormalViews out;
  for (View v : kAllViews) {
    const Image& decoded = views[v].normals;
    Image encoded(decoded.width, decoded.height, 4);
    const int64_t pixels = int64_t(decoded.pixel_count());
#pragma omp parallel for schedule(static) if (pixels > 65536)
    for (int64_t p = 0; p < pixels; ++p) {
      const float* in = decoded.data.data() + p * 4;
      float* px = encoded.data.data() + p * 4;
      for (int c = 0; c < 3; ++c) px[c] = 0.5f * (in[c] + 1.f);
      px[3] = in[3];
    }
    out.normal_maps.push_back(std::move(encoded));
    out.cameras.push_back(view_camera(v, decoded.width));
  }
  return out;
}

void check_normal_views(const NormalViews& views, const std::string& what) {
  require(!views.normal_maps.empty() && views.normal_maps.size() == views.cameras.size(),
          what + ": one normal map per camera");
  for (size_t i = 0; i < views.cameras.size(); ++i) {
    const Image& map = views.normal_maps[i];
    require(map.width == views.cameras[i].width && map.height == views.cameras[i].height,
            what + ": normal map " + std::to_string(i) + " does not match its camera resolution");
    require(map.channels == 4, what + ": normal map " + std::to_string(i) + " must be RGBA (alpha = mask)");
  }
}

NormalViews at_resolution(const NormalViews& views, int max_resolution) {
  check_normal_views(views, "normal views");
  const std::vector<Image>& normal_maps = views.normal_maps;
  NormalViews out{std::vector<Image>(normal_maps.size()), views.cameras};
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
    out.normal_maps[size_t(i)] = resize_premultiplied(map, w, h);
    // The projection maps to normalized device coordinates: only the pixel grid changes.
    out.cameras[size_t(i)].width = w;
    out.cameras[size_t(i)].height = h;
  }
  return out;
}

}  // namespace u3d
