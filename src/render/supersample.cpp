#include "render/supersample.h"

#include "core/error.h"

namespace u3d {

Image downsample_alpha_weighted(const Image& in, int factor) {
  require(factor >= 1, "supersampling factor must be at least 1");
  require(in.channels == 4, "downsample_alpha_weighted expects an RGBA image");
  require(in.width % factor == 0 && in.height % factor == 0, "image size is not a multiple of the supersampling factor");
  if (factor == 1) return in;
  const int w = in.width / factor, h = in.height / factor;
  Image out(w, h, 4, 0.f);
  const float inv_samples = 1.f / float(factor * factor);
#pragma omp parallel for schedule(static) if (size_t(w) * h >= 128 * 128)
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float r = 0, g = 0, b = 0, a = 0;
      for (int sy = 0; sy < factor; ++sy)
        for (int sx = 0; sx < factor; ++sx) {
          const float* p = in.pixel(x * factor + sx, y * factor + sy);
          r += p[0] * p[3];
          g += p[1] * p[3];
          b += p[2] * p[3];
          a += p[3];
        }
      float* q = out.pixel(x, y);
      if (a > 0.f) {
        q[0] = r / a;
        q[1] = g / a;
        q[2] = b / a;
      }
      q[3] = a * inv_samples;
    }
  return out;
}

}  // namespace u3d
