#include "isomer/silhouette_check.h"

#include "render/rasterizer.h"

namespace u3d {

std::array<float, 4> silhouette_iou(const Mesh& mesh, const ViewSet& views) {
  std::array<float, 4> iou{};
  for (View v : kAllViews) {
    const Image& mask = views[v].normals;
    const RasterBuffer buf = rasterize(mesh, view_camera(v, mask.width));
    size_t inter = 0, uni = 0;
    for (size_t p = 0; p < buf.pixel_count(); ++p) {
      const bool a = buf.covered(p), b = is_foreground(mask.data[p * 4 + 3]);
      inter += a && b;
      uni += a || b;
    }
    iou[size_t(v)] = uni ? float(inter) / float(uni) : 1.f;
  }
  return iou;
}

}  // namespace u3d
