#include "isomer/reconstruction_losses.h"

#include <cmath>
#include <numeric>

#include "core/error.h"

namespace u3d {

NormalTarget make_normal_target(const Image& normal_map) {
  require(normal_map.channels == 4, "normal map must be RGBA (alpha = mask)");
  NormalTarget t;
  t.rgba = Image(normal_map.width, normal_map.height, 4);
  for (size_t p = 0; p < normal_map.pixel_count(); ++p) {
    const float* in = normal_map.data.data() + p * 4;
    float* out = t.rgba.data.data() + p * 4;
    const float a = in[3];
    // Faint alpha is treated as background, as the official target preparation does.
    for (int c = 0; c < 3; ++c) out[c] = a > 0.05f ? in[c] * a : 0.f;
    out[3] = a;
    if (a < 0.5f) {
      t.background.push_back(int32_t(p));
      t.background_alpha_sq += double(a) * a;
    }
  }
  return t;
}

double masked_image_l2(NormalRenderer& renderer, const std::vector<const Image*>& references, int channels,
                       float weight) {
  require(references.size() == renderer.view_count(), "one reference image per view");
  const int views = int(renderer.view_count());
  for (int i = 0; i < views; ++i) {
    const Image& ref = *references[size_t(i)];
    const Image& image = renderer.view(size_t(i)).image;
    require(ref.width == image.width && ref.height == image.height && ref.channels == 4,
            "reference image must match the view resolution and be RGBA");
  }
  size_t count = 0;
  for (int i = 0; i < views; ++i) count += renderer.view(size_t(i)).opaque_pixels;
  const std::vector<int>& order = renderer.largest_first();
  if (count == 0) return 0.0;
  const float scale = weight / float(count * channels);
  std::vector<double> view_total(size_t(views), 0.0);  // summed in view order: deterministic
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < views; ++k) {
    const int i = order[size_t(k)];
    DifferentiableView& v = renderer.view(size_t(i));
    const Image& ref = *references[size_t(i)];
    double total = 0.0;  // in a register: summing into view_total[i] made a store-load chain per pixel
    for (int32_t p : v.active) {
      const float* img = v.image.data.data() + size_t(p) * 4;
      if (img[3] <= 0.5f) continue;
      const float* r = ref.data.data() + size_t(p) * 4;
      float* g = v.grad_image.data.data() + size_t(p) * 4;
      // One double addition per pixel: a chain of them per channel was the loop's bottleneck.
      float pixel_total = 0.f;
      for (int c = 0; c < channels; ++c) {
        const float d = img[c] - r[c];
        pixel_total += d * d;
        g[c] += 2.f * scale * d;
      }
      total += pixel_total;
    }
    view_total[size_t(i)] = total;
  }
  return std::accumulate(view_total.begin(), view_total.end(), 0.0) * scale;
}

double background_alpha_l2(NormalRenderer& renderer, const std::vector<NormalTarget>& targets, float weight) {
  require(targets.size() == renderer.view_count(), "one target per view");
  size_t count = 0;
  for (const NormalTarget& t : targets) count += t.background.size();
  if (count == 0) return 0.0;
  const float scale = weight / float(count);
  const int views = int(renderer.view_count());
  std::vector<double> view_total(size_t(views), 0.0);
  const std::vector<int>& order = renderer.largest_first();
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < views; ++k) {
    const int i = order[size_t(k)];
    DifferentiableView& v = renderer.view(size_t(i));
    const NormalTarget& t = targets[size_t(i)];
    // Off the rendered footprint the alpha is 0: those pixels add the constant target alpha^2.
    double total = t.background_alpha_sq;
    for (int32_t p : v.active) {
      const float target_alpha = t.rgba.data[size_t(p) * 4 + 3];
      if (target_alpha >= 0.5f) continue;
      const float d = v.image.data[size_t(p) * 4 + 3] - target_alpha;
      total += double(d) * d - double(target_alpha) * target_alpha;
      v.grad_image.data[size_t(p) * 4 + 3] += 2.f * scale * d;
    }
    view_total[size_t(i)] = total;
  }
  return std::accumulate(view_total.begin(), view_total.end(), 0.0) * scale;
}

double expansion_loss(const std::vector<Vec3f>& normals, float weight, std::vector<Vec3f>& grad_positions) {
  if (normals.empty()) return 0.0;
  const float scale = weight / float(3 * normals.size());
  double total = 0.0;
  for (size_t v = 0; v < normals.size(); ++v) {
    total += 0.5 * normals[v].squaredNorm();
    grad_positions[v] -= scale * normals[v];
  }
  return total * scale;
}

double out_of_box_loss(const std::vector<Vec3f>& positions, float limit, float weight,
                       std::vector<Vec3f>& grad_positions) {
  if (positions.empty()) return 0.0;
  const float scale = weight / float(3 * positions.size());
  double total = 0.0;
  for (size_t v = 0; v < positions.size(); ++v) {
    for (int c = 0; c < 3; ++c) {
      const float excess = std::abs(positions[v][c]) - limit;
      if (excess <= 0.f) continue;
      total += double(excess) * excess;
      grad_positions[v][c] += 2.f * scale * excess * (positions[v][c] > 0.f ? 1.f : -1.f);
    }
  }
  return total * scale;
}

}  // namespace u3d
