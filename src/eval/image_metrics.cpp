#include "eval/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace u3d {

namespace {

void require_comparable(const Image& a, const Image& b) {
  require(a.width == b.width && a.height == b.height,
          "image metrics need equal sizes, got " + std::to_string(a.width) + "x" + std::to_string(a.height) + " and " +
              std::to_string(b.width) + "x" + std::to_string(b.height));
  require(a.channels >= 3 && b.channels >= 3, "image metrics need RGB or RGBA images");
  require(!a.empty(), "image metrics need non-empty images");
}

cv::Mat channel(const Image& img, int c) {
  cv::Mat m(img.height, img.width, CV_64F);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) m.at<double>(y, x) = img.at(x, y, c);
  return m;
}

cv::Mat gaussian(const cv::Mat& m) {
  cv::Mat out;
  cv::GaussianBlur(m, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT);
  return out;
}

}  // namespace

double mean_squared_error(const Image& a, const Image& b) {
  require_comparable(a, b);
  double sum = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x)
      for (int c = 0; c < 3; ++c) {
        double d = double(a.at(x, y, c)) - double(b.at(x, y, c));
        sum += d * d;
      }
  return sum / (3.0 * double(a.pixel_count()));
}

double psnr(const Image& a, const Image& b) {
  double mse = mean_squared_error(a, b);
  if (mse <= 0) return kPsnrCapDb;
  return std::min(kPsnrCapDb, -10.0 * std::log10(mse));
}

double ssim(const Image& a, const Image& b) {
  require_comparable(a, b);
  const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
  double total = 0;
  for (int c = 0; c < 3; ++c) {
    cv::Mat x = channel(a, c), y = channel(b, c);
    cv::Mat mx = gaussian(x), my = gaussian(y);
    cv::Mat sxx = gaussian(x.mul(x)) - mx.mul(mx);
    cv::Mat syy = gaussian(y.mul(y)) - my.mul(my);
    cv::Mat sxy = gaussian(x.mul(y)) - mx.mul(my);
    cv::Mat numerator = (2 * mx.mul(my) + c1).mul(2 * sxy + c2);
    cv::Mat denominator = (mx.mul(mx) + my.mul(my) + c1).mul(sxx + syy + c2);
    cv::Mat map;
    cv::divide(numerator, denominator, map);
    total += cv::mean(map)[0];
  }
  return total / 3.0;
}

}  // namespace u3d
