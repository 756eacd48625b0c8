#include "nn/preprocess/pil_resize.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"

namespace u3d::nn {

namespace {

constexpr int kPrecisionBits = 32 - 8 - 2;  // Pillow's fixed-point precision for 8-bit images

double bilinear_kernel(double x) {
  x = std::abs(x);
  return x < 1.0 ? 1.0 - x : 0.0;
}

double bicubic_kernel(double x) {
  constexpr double a = -0.5;
  x = std::abs(x);
  if (x < 1.0) return ((a + 2.0) * x - (a + 3.0)) * x * x + 1;
  if (x < 2.0) return (((x - 5) * x + 8) * x - 4) * a;
  return 0.0;
}

double sinc(double x) {
  if (x == 0.0) return 1.0;
  x *= M_PI;
  return std::sin(x) / x;
}

double lanczos_kernel(double x) { return (-3.0 <= x && x < 3.0) ? sinc(x) * sinc(x / 3) : 0.0; }

struct Filter {
  double (*kernel)(double);
  double support;
};

Filter filter_of(PilFilter f) {
  switch (f) {
    case PilFilter::Bilinear: return {bilinear_kernel, 1.0};
    case PilFilter::Bicubic: return {bicubic_kernel, 2.0};
    case PilFilter::Lanczos: return {lanczos_kernel, 3.0};
  }
  throw Error("unknown resampling filter");
}

// For every output pixel along one axis: the first input index, the tap count, and `ksize` fixed-point
// weights (Pillow's precompute_coeffs + normalize_coeffs_8bpc).
struct Coefficients {
  int ksize = 0;
  std::vector<int> first, count;
  std::vector<int32_t> weights;
};

Coefficients precompute(int in_size, int out_size, const Filter& filter) {
  const double scale = static_cast<double>(in_size) / out_size;
  const double filterscale = std::max(scale, 1.0);
  const double support = filter.support * filterscale;
  Coefficients c;
  c.ksize = static_cast<int>(std::ceil(support)) * 2 + 1;
  c.first.resize(out_size);
  c.count.resize(out_size);
  c.weights.assign(static_cast<size_t>(out_size) * c.ksize, 0);
  std::vector<double> k(c.ksize);
  for (int xx = 0; xx < out_size; ++xx) {
    const double center = (xx + 0.5) * scale;
    const double ss = 1.0 / filterscale;
    // Pillow rounds with (int)(v + 0.5): truncation toward zero, kept for identical bounds.
    int xmin = static_cast<int>(center - support + 0.5);
    if (xmin < 0) xmin = 0;
    int xmax = static_cast<int>(center + support + 0.5);
    if (xmax > in_size) xmax = in_size;
    xmax -= xmin;
    double ww = 0.0;
    for (int x = 0; x < xmax; ++x) {
      k[x] = filter.kernel((x + xmin - center + 0.5) * ss);
      ww += k[x];
    }
    for (int x = 0; x < xmax; ++x) {
      const double w = ww != 0.0 ? k[x] / ww : k[x];
      const double fixed = w * (1 << kPrecisionBits);
      c.weights[static_cast<size_t>(xx) * c.ksize + x] = static_cast<int32_t>(w < 0 ? -0.5 + fixed : 0.5 + fixed);
    }
    c.first[xx] = xmin;
    c.count[xx] = xmax;
  }
  return c;
}

uint8_t clip8(int32_t v) {
  v >>= kPrecisionBits;  // arithmetic shift: floor, as Pillow
  return static_cast<uint8_t>(std::clamp(v, 0, 255));
}

// Resamples along one axis of a [rows, cols, channels] buffer; `along_columns` picks the axis.
std::vector<uint8_t> resample_axis(const std::vector<uint8_t>& in, int rows, int cols, int channels, bool horizontal,
                                   int out_size, const Filter& filter) {
  const int in_size = horizontal ? cols : rows;
  const Coefficients c = precompute(in_size, out_size, filter);
  const int out_rows = horizontal ? rows : out_size;
  const int out_cols = horizontal ? out_size : cols;
  std::vector<uint8_t> out(static_cast<size_t>(out_rows) * out_cols * channels);
  for (int y = 0; y < out_rows; ++y) {
    for (int x = 0; x < out_cols; ++x) {
      const int o = horizontal ? x : y;
      const int32_t* k = &c.weights[static_cast<size_t>(o) * c.ksize];
      for (int ch = 0; ch < channels; ++ch) {
        int32_t ss = 1 << (kPrecisionBits - 1);
        for (int i = 0; i < c.count[o]; ++i) {
          const int sy = horizontal ? y : c.first[o] + i;
          const int sx = horizontal ? c.first[o] + i : x;
          ss += static_cast<int32_t>(in[(static_cast<size_t>(sy) * cols + sx) * channels + ch]) * k[i];
        }
        out[(static_cast<size_t>(y) * out_cols + x) * channels + ch] = clip8(ss);
      }
    }
  }
  return out;
}

}  // namespace

PilFilter pil_filter_from_code(int code) {
  switch (code) {
    case 1: return PilFilter::Lanczos;
    case 2: return PilFilter::Bilinear;
    case 3: return PilFilter::Bicubic;
    default:
      throw Error("resampling filter " + std::to_string(code) +
                  " is not supported (1 = Lanczos, 2 = bilinear, 3 = bicubic are)");
  }
}

torch::Tensor pil_resize(const torch::Tensor& image, int64_t out_width, int64_t out_height, PilFilter filter) {
  if (image.dim() != 3 || image.scalar_type() != torch::kUInt8)
    throw Error("pil_resize: expected a uint8 [H, W, C] image, got " + std::string(c10::toString(image.scalar_type())) +
                " " + c10::str(image.sizes()));
  if (out_width <= 0 || out_height <= 0 || image.size(0) == 0 || image.size(1) == 0)
    throw Error("pil_resize: cannot resize a " + std::to_string(image.size(1)) + "x" + std::to_string(image.size(0)) +
                " image to " + std::to_string(out_width) + "x" + std::to_string(out_height));
  torch::Tensor src = image.to(torch::kCPU).contiguous();
  int rows = static_cast<int>(src.size(0)), cols = static_cast<int>(src.size(1));
  const int channels = static_cast<int>(src.size(2));
  std::vector<uint8_t> buf(src.data_ptr<uint8_t>(), src.data_ptr<uint8_t>() + src.numel());
  const Filter f = filter_of(filter);
  // Pillow skips a pass whose size does not change, and runs horizontal before vertical.
  if (out_width != cols) {
    buf = resample_axis(buf, rows, cols, channels, true, static_cast<int>(out_width), f);
    cols = static_cast<int>(out_width);
  }
  if (out_height != rows) {
    buf = resample_axis(buf, rows, cols, channels, false, static_cast<int>(out_height), f);
    rows = static_cast<int>(out_height);
  }
  return torch::from_blob(buf.data(), {rows, cols, channels}, torch::kUInt8).clone();
}

torch::Tensor image_to_uint8_rgb(const Image& image) {
  if (image.channels != 3 && image.channels != 4)
    throw Error("expected an RGB or RGBA image, got " + std::to_string(image.channels) + " channels");
  torch::Tensor out = torch::empty({image.height, image.width, 3}, torch::kUInt8);
  uint8_t* dst = out.data_ptr<uint8_t>();
  for (size_t p = 0; p < image.pixel_count(); ++p)
    for (int c = 0; c < 3; ++c) {
      const float v = std::clamp(image.data[p * image.channels + c], 0.0f, 1.0f);
      dst[p * 3 + c] = static_cast<uint8_t>(std::lround(v * 255.0f));
    }
  return out;
}

}  // namespace u3d::nn
