#include "nn/pipelines/matting.h"

#include <cmath>

#include "core/error.h"
#include "nn/preprocess/pil_resize.h"

namespace u3d::nn {
namespace {

constexpr int64_t kU2NetResolution = 320;
constexpr int64_t kIsNetResolution = 1024;
constexpr double kImageNetMean[3] = {0.485, 0.456, 0.406};
constexpr double kImageNetStd[3] = {0.229, 0.224, 0.225};

void check_image(const torch::Tensor& image, const char* what, bool allow_alpha) {
  require(image.dim() == 3 && image.scalar_type() == torch::kUInt8 &&
              (image.size(2) == 3 || (allow_alpha && image.size(2) == 4)),
          std::string(what) + ": expected a uint8 image [H, W, " + (allow_alpha ? "3|4]" : "3]"));
}

// PIL's rounded division by 255 of a product of two 8-bit values (its blend and composite).
inline uint8_t mul_div255(int a, int b) {
  const int t = a * b + 128;
  return static_cast<uint8_t>((t + (t >> 8)) >> 8);
}

}  // namespace

int64_t default_matting_resolution(const U2NetConfig& config) {
  return config.isnet ? kIsNetResolution : kU2NetResolution;
}

torch::Tensor imgly_resize_bilinear(const torch::Tensor& image, int64_t width, int64_t height) {
  const torch::Tensor src = image.contiguous();
  const int64_t h = src.size(0), w = src.size(1), c = src.size(2);
  torch::Tensor out = torch::empty({height, width, c}, torch::kUInt8);
  const uint8_t* in = src.data_ptr<uint8_t>();
  uint8_t* dst = out.data_ptr<uint8_t>();
  const double sx = double(w) / double(width), sy = double(h) / double(height);
  for (int64_t y = 0; y < height; ++y) {
    const double fy = y * sy;
    const auto y1 = static_cast<int64_t>(std::floor(fy));
    const int64_t y2 = std::min(static_cast<int64_t>(std::ceil(fy)), h - 1);
    const double dy = fy - y1;
    for (int64_t x = 0; x < width; ++x) {
      const double fx = x * sx;
      const auto x1 = static_cast<int64_t>(std::floor(fx));
      const int64_t x2 = std::min(static_cast<int64_t>(std::ceil(fx)), w - 1);
      const double dx = fx - x1;
      for (int64_t k = 0; k < c; ++k) {
        const double p11 = in[(y1 * w + x1) * c + k], p12 = in[(y1 * w + x2) * c + k];
        const double p21 = in[(y2 * w + x1) * c + k], p22 = in[(y2 * w + x2) * c + k];
        const double v = (1 - dx) * (1 - dy) * p11 + dx * (1 - dy) * p12 + (1 - dx) * dy * p21 + dx * dy * p22;
        dst[(y * width + x) * c + k] = static_cast<uint8_t>(std::clamp(std::floor(v + 0.5), 0.0, 255.0));
      }
    }
  }
  return out;
}

torch::Tensor matting_input(const torch::Tensor& rgb, const U2NetConfig& config, MattingStyle style,
                            int64_t resolution) {
  check_image(rgb, "matting_input", false);
  if (style == MattingStyle::kImgly) {
    const torch::Tensor resized = imgly_resize_bilinear(rgb, resolution, resolution).to(torch::kFloat);
    return ((resized - 128.0) / 256.0).permute({2, 0, 1}).unsqueeze(0).contiguous();
  }
  torch::Tensor a = pil_resize(rgb, resolution, resolution, PilFilter::Lanczos).to(torch::kDouble);
  a = a / std::max(a.max().item<double>(), 1e-6);
  const torch::Tensor mean =
      config.isnet ? torch::full({3}, 0.5, torch::kDouble)
                   : torch::tensor({kImageNetMean[0], kImageNetMean[1], kImageNetMean[2]}, torch::kDouble);
  const torch::Tensor deviation =
      config.isnet ? torch::ones({3}, torch::kDouble)
                   : torch::tensor({kImageNetStd[0], kImageNetStd[1], kImageNetStd[2]}, torch::kDouble);
  return ((a - mean) / deviation).permute({2, 0, 1}).unsqueeze(0).to(torch::kFloat).contiguous();
}

torch::Tensor matting_mask(const torch::Tensor& prediction, MattingStyle style, int64_t width, int64_t height) {
  const torch::Tensor p = prediction.reshape({prediction.size(-2), prediction.size(-1)}).to(torch::kFloat);
  if (style == MattingStyle::kImgly) {
    const torch::Tensor u8 = (p.to(torch::kDouble) * 255.0).floor().clamp(0.0, 255.0).to(torch::kUInt8);
    return imgly_resize_bilinear(u8.unsqueeze(2), width, height).squeeze(2);
  }
  const float hi = p.max().item<float>(), lo = p.min().item<float>();
  const torch::Tensor unit = hi > lo ? (p - lo) / (hi - lo) : torch::zeros_like(p);
  const torch::Tensor u8 = (unit.clamp(0.0, 1.0) * 255.0f).to(torch::kUInt8);  // truncates, as numpy's astype
  return pil_resize(u8.unsqueeze(2), width, height, PilFilter::Lanczos).squeeze(2);
}

torch::Tensor cutout(const torch::Tensor& image, const torch::Tensor& mask, MattingStyle style) {
  check_image(image, "cutout", true);
  require(mask.dim() == 2 && mask.scalar_type() == torch::kUInt8 && mask.size(0) == image.size(0) &&
              mask.size(1) == image.size(1),
          "cutout: the mask must be uint8 [H, W] of the image's size");
  const torch::Tensor src = image.contiguous(), m = mask.contiguous();
  const int64_t pixels = image.size(0) * image.size(1), c = image.size(2);
  torch::Tensor out = torch::empty({image.size(0), image.size(1), 4}, torch::kUInt8);
  const uint8_t* in = src.data_ptr<uint8_t>();
  const uint8_t* mp = m.data_ptr<uint8_t>();
  uint8_t* dst = out.data_ptr<uint8_t>();
  for (int64_t i = 0; i < pixels; ++i) {
    const int alpha = c == 4 ? in[i * c + 3] : 255;
    for (int k = 0; k < 3; ++k)
      dst[i * 4 + k] = style == MattingStyle::kRembg ? mul_div255(in[i * c + k], mp[i]) : in[i * c + k];
    dst[i * 4 + 3] = style == MattingStyle::kRembg ? mul_div255(alpha, mp[i]) : mp[i];
  }
  return out;
}

std::unique_ptr<MattingModel> MattingModel::load(const std::filesystem::path& path, Precision precision) {
  check_precision_supported(precision, torch::kCPU);
  const TensorMap weights = read_u2net_weights(path);
  bool fp16 = false;
  for (const auto& [name, tensor] : weights) fp16 = fp16 || tensor.scalar_type() == torch::kHalf;
  auto m = std::make_unique<MattingModel>();
  m->net = build_u2net(weights, path.string());
  m->style = m->net->config.isnet && fp16 ? MattingStyle::kImgly : MattingStyle::kRembg;
  m->resolution = default_matting_resolution(m->net->config);
  set_precision(*m->net, precision);
  return m;
}

torch::Tensor MattingModel::matte(const torch::Tensor& rgb) {
  torch::NoGradGuard no_grad;
  const torch::Tensor input = matting_input(rgb, net->config, style, resolution);
  return matting_mask(net->forward(input)[0], style, rgb.size(1), rgb.size(0));
}

}  // namespace u3d::nn
