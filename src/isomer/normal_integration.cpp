#include "isomer/normal_integration.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace u3d {
namespace {

// Slopes in pixel units: u = column (right), v = row (down). With z toward the camera and camera y
// up, dz/du = -n_x / n_z and dz/dv = +n_y / n_z.
cv::Mat slope_field(const std::vector<Vec3f>& normals, const std::vector<uint8_t>& mask, int w, int h,
                    float max_slope) {
  cv::Mat g(h, w, CV_32FC2, cv::Scalar(0, 0));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!mask[i]) continue;
      const Vec3f& n = normals[i];
      Eigen::Vector2f s(-n.x(), n.y());
      s /= std::max(n.z(), 1e-4f);
      if (!(s.norm() <= max_slope)) s = s.norm() > 0 ? Eigen::Vector2f(s.normalized() * max_slope) : Eigen::Vector2f(0, 0);
      g.at<cv::Vec2f>(y, x) = {s.x(), s.y()};
    }
  return g;
}

// Copies slopes a few pixels into the background so bilinear rotation does not blend the rim
// slopes with zeros.
void extend_into_background(cv::Mat& g, cv::Mat& known, int passes) {
  for (int pass = 0; pass < passes; ++pass) {
    cv::Mat next_known = known.clone();
    for (int y = 0; y < g.rows; ++y)
      for (int x = 0; x < g.cols; ++x) {
        if (known.at<uint8_t>(y, x)) continue;
        cv::Vec2f sum(0, 0);
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            int yy = y + dy, xx = x + dx;
            if (yy < 0 || xx < 0 || yy >= g.rows || xx >= g.cols || !known.at<uint8_t>(yy, xx)) continue;
            sum += g.at<cv::Vec2f>(yy, xx);
            ++count;
          }
        if (count) {
          g.at<cv::Vec2f>(y, x) = sum / float(count);
          next_known.at<uint8_t>(y, x) = 1;
        }
      }
    known = next_known;
  }
}

// Running trapezoid sums of a slope field along rows or columns, restarting at zero on entering the
// mask. One state per line, so all four walks visit the canvas row by row (cache friendly).
struct LineSums {
  std::vector<float> height, prev;
  std::vector<uint8_t> was_inside;
  explicit LineSums(int lines) : height(lines, 0.f), prev(lines, 0.f), was_inside(lines, 0) {}
  // Advances line `k` by one pixel of slope `s` (already signed for the walk direction).
  float step(int k, bool inside, float s) {
    if (!inside) {
      was_inside[k] = 0;
      return 0.f;
    }
    height[k] = was_inside[k] ? height[k] + 0.5f * (prev[k] + s) : 0.5f * s;
    prev[k] = s;
    was_inside[k] = 1;
    return height[k];
  }
};

// floor() for coordinates above -kOffset without a libm call per pixel (exact: a float plus the
// offset is representable in a double).
inline int fast_floor(float x) {
  constexpr int kOffset = 1 << 20;
  return int(double(x) + kOffset) - kOffset;
}

// Bilinear sample of an interleaved two-channel field, zero outside the image.
inline Eigen::Vector2f sample2(const float* img, int w, int h, float x, float y) {
  const int x0 = fast_floor(x), y0 = fast_floor(y);
  const float fx = x - x0, fy = y - y0;
  if (x0 >= 0 && y0 >= 0 && x0 + 1 < w && y0 + 1 < h) {  // interior: no bounds checks
    const float* p = img + 2 * (size_t(y0) * w + x0);
    const float* q = p + 2 * size_t(w);
    const float a = (1 - fx) * (1 - fy), b = fx * (1 - fy), c = (1 - fx) * fy, d = fx * fy;
    return {a * p[0] + b * p[2] + c * q[0] + d * q[2], a * p[1] + b * p[3] + c * q[1] + d * q[3]};
  }
  Eigen::Vector2f out(0, 0);
  for (int dy = 0; dy <= 1; ++dy)
    for (int dx = 0; dx <= 1; ++dx) {
      const int xx = x0 + dx, yy = y0 + dy;
      if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
      const float wgt = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
      out += wgt * Eigen::Vector2f(img[2 * (size_t(yy) * w + xx)], img[2 * (size_t(yy) * w + xx) + 1]);
    }
  return out;
}

// Bilinear sample with zero outside the image.
inline float sample(const float* img, int w, int h, float x, float y) {
  const int x0 = fast_floor(x), y0 = fast_floor(y);
  const float fx = x - x0, fy = y - y0;
  auto at = [&](int xx, int yy) { return (xx < 0 || yy < 0 || xx >= w || yy >= h) ? 0.f : img[size_t(yy) * w + xx]; };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

}  // namespace

std::vector<float> integrate_normal_map(const std::vector<Vec3f>& normals, const std::vector<uint8_t>& mask, int width,
                                        int height, const NormalIntegrationOptions& options) {
  require(width > 0 && height > 0 && normals.size() == size_t(width) * height && mask.size() == normals.size(),
          "integrate_normal_map: normals and mask must both have width * height entries");
  require(options.rotations >= 1, "integrate_normal_map: rotations must be at least 1");
  const size_t n = normals.size();

  cv::Mat slopes = slope_field(normals, mask, width, height, options.max_slope);
  Eigen::Vector2d mean_slope(0, 0), centroid(0, 0);
  size_t fg = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (mask[size_t(y) * width + x]) {
        const cv::Vec2f s = slopes.at<cv::Vec2f>(y, x);
        mean_slope += Eigen::Vector2d(s[0], s[1]);
        centroid += Eigen::Vector2d(x, y);
        ++fg;
      }
  if (fg == 0) return std::vector<float>(n, 0.f);
  mean_slope /= double(fg);
  centroid /= double(fg);
  if (!options.remove_mean_slope) mean_slope.setZero();
  slopes -= cv::Scalar(mean_slope.x(), mean_slope.y());

  cv::Mat known(height, width, CV_8U);
  for (size_t i = 0; i < n; ++i) known.data[i] = mask[i] ? 1 : 0;
  extend_into_background(slopes, known, 2);

  const float* slopes_src = reinterpret_cast<const float*>(slopes.data);  // interleaved (u, v), continuous
  std::vector<float> mask_src(n);
  for (size_t i = 0; i < n; ++i) mask_src[i] = mask[i] ? 1.f : 0.f;
  std::vector<int> fg_pixels;
  Eigen::Vector2i box_min(width, height), box_max(-1, -1);
  for (size_t i = 0; i < n; ++i)
    if (mask[i]) {
      fg_pixels.push_back(int(i));
      const Eigen::Vector2i p(int(i % width), int(i / width));
      box_min = box_min.cwiseMin(p), box_max = box_max.cwiseMax(p);
    }

  // A canvas large enough for the map under any rotation, with the map's centre at its centre.
  const int side = int(std::ceil(std::hypot(double(width), double(height)))) + 2;
  const float cx = 0.5f * (width - 1), cy = 0.5f * (height - 1), cc = 0.5f * (side - 1);
  const int rotations = options.rotations;
  std::vector<double> total(n, 0.0);
#pragma omp parallel
  {
    std::vector<float> su(size_t(side) * side), sv(su.size()), sum(su.size());
    std::vector<uint8_t> inside(su.size());
    std::vector<double> local(n, 0.0);
#pragma omp for schedule(dynamic)
    for (int r = 0; r < rotations; ++r) {
      // Canvas P = A (p - c) + C with A = [[co, si], [-si, co]]; slopes, a gradient, turn with A.
      const double angle = 0.5 * M_PI * r / rotations;
      const float co = float(std::cos(angle)), si = float(std::sin(angle));
      // Only the window holding the rotated mask bounding box needs work.
      int X0 = side, X1 = -1, Y0 = side, Y1 = -1;
      for (int corner = 0; corner < 4; ++corner) {
        const float dx = float(corner & 1 ? box_max.x() + 1 : box_min.x() - 1) - cx;
        const float dy = float(corner & 2 ? box_max.y() + 1 : box_min.y() - 1) - cy;
        const float X = co * dx + si * dy + cc, Y = -si * dx + co * dy + cc;
        X0 = std::min(X0, int(std::floor(X))), X1 = std::max(X1, int(std::ceil(X)));
        Y0 = std::min(Y0, int(std::floor(Y))), Y1 = std::max(Y1, int(std::ceil(Y)));
      }
      X0 = std::max(X0, 0), Y0 = std::max(Y0, 0), X1 = std::min(X1, side - 1), Y1 = std::min(Y1, side - 1);
      for (int Y = Y0; Y <= Y1; ++Y)
        for (int X = X0; X <= X1; ++X) {
          const float dx = X - cc, dy = Y - cc;
          const float x = co * dx - si * dy + cx, y = si * dx + co * dy + cy;
          const size_t i = size_t(Y) * side + X;
          // Nearest pixel decides inside/outside (cheap); slopes are interpolated.
          const int xn = fast_floor(x + 0.5f), yn = fast_floor(y + 0.5f);
          inside[i] = xn >= 0 && yn >= 0 && xn < width && yn < height && mask_src[size_t(yn) * width + xn] > 0.f;
          if (!inside[i]) continue;
          const Eigen::Vector2f g = sample2(slopes_src, width, height, x, y);
          const float gu = g.x(), gv = g.y();
          su[i] = co * gu + si * gv;
          sv[i] = -si * gu + co * gv;
        }
      std::fill(sum.begin(), sum.end(), 0.f);
      LineSums rows_fwd(side), rows_back(side), cols_down(side), cols_up(side);
      for (int Y = Y0; Y <= Y1; ++Y) {
        const size_t row = size_t(Y) * side;
        for (int X = X0; X <= X1; ++X) {
          const size_t i = row + X;
          sum[i] += rows_fwd.step(Y, inside[i], su[i]) + cols_down.step(X, inside[i], sv[i]);
        }
        for (int X = X1; X >= X0; --X) sum[row + X] += rows_back.step(Y, inside[row + X], -su[row + X]);
      }
      for (int Y = Y1; Y >= Y0; --Y) {
        const size_t row = size_t(Y) * side;
        for (int X = X0; X <= X1; ++X) sum[row + X] += cols_up.step(X, inside[row + X], -sv[row + X]);
      }
      for (int i : fg_pixels) {
        const float dx = float(i % width) - cx, dy = float(i / width) - cy;
        local[i] += sample(sum.data(), side, side, co * dx + si * dy + cc, -si * dx + co * dy + cc);
      }
    }
#pragma omp critical
    for (size_t i = 0; i < n; ++i) total[i] += local[i];
  }

  std::vector<float> heights(n, 0.f);
  const float scale = 1.f / (4.f * float(rotations));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      if (!mask[i]) continue;
      heights[i] = float(total[i]) * scale + float(mean_slope.x() * (x - centroid.x()) + mean_slope.y() * (y - centroid.y()));
    }
  return heights;
}

}  // namespace u3d
