#include "render/preview.h"

#include <algorithm>

#include "render/render_view.h"

namespace u3d {
namespace {

constexpr float kBackground = 0.9f;

// Shaded colour render of one camera, composited over the background.
Image shaded_frame(const Mesh& mesh, const Camera& camera) {
  RenderSettings settings;
  settings.normal_space = NormalSpace::Camera;
  settings.ssaa = 2;
  const RenderedView view = render_view(mesh, camera, settings);
  Image out(camera.width, camera.height, 3, kBackground);
  for (size_t p = 0; p < out.pixel_count(); ++p) {
    const float alpha = view.rgb.data[p * 4 + 3];
    const float facing = std::max(0.f, 2.f * view.normal.data[p * 4 + 2] - 1.f);  // camera-space n_z
    const float light = 0.55f + 0.45f * facing;
    for (int c = 0; c < 3; ++c)
      out.data[p * 3 + c] = alpha * light * view.rgb.data[p * 4 + c] + (1.f - alpha) * kBackground;
  }
  return out;
}

Image side_by_side(const std::vector<Image>& frames) {
  const int w = frames.front().width, h = frames.front().height;
  Image out(w * int(frames.size()), h, 3);
  for (size_t f = 0; f < frames.size(); ++f)
    for (int y = 0; y < h; ++y)
      std::copy_n(frames[f].pixel(0, y), size_t(w) * 3, out.pixel(int(f) * w, y));
  return out;
}

}  // namespace

Image preview_four_views(const Mesh& mesh, int resolution) {
  std::vector<Image> frames;
  for (View v : kAllViews) frames.push_back(shaded_frame(mesh, view_camera(v, resolution)));
  return side_by_side(frames);
}

Image preview_turntable(const Mesh& mesh, int frames, int resolution, float elevation_deg) {
  std::vector<Image> out;
  for (int f = 0; f < frames; ++f)
    out.push_back(shaded_frame(
        mesh, orthographic_camera(orbit_direction(360.f * f / frames, elevation_deg), resolution, resolution)));
  return side_by_side(out);
}

}  // namespace u3d
