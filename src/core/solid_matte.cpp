#include "core/solid_matte.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>

#include "core/error.h"

namespace u3d {

Image solid_matte(const Image& alpha) {
  require(alpha.channels == 1 && !alpha.empty(), "solid_matte: expected a 1-channel alpha image");
  const int w = alpha.width, h = alpha.height;
  cv::Mat below_core(h, w, CV_8U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) below_core.at<uint8_t>(y, x) = alpha.at(x, y, 0) < kSolidMatteCore ? 1 : 0;
  // The regions below the core; those with a pixel on the image border are the outside.
  cv::Mat labels;
  const int count = cv::connectedComponents(below_core, labels, 4, CV_32S);
  std::vector<char> outside(size_t(count), 0);
  for (int x = 0; x < w; ++x) outside[labels.at<int>(0, x)] = outside[labels.at<int>(h - 1, x)] = 1;
  for (int y = 0; y < h; ++y) outside[labels.at<int>(y, 0)] = outside[labels.at<int>(y, w - 1)] = 1;
  // The subject (the core and the enclosed regions), and the clear regions inside it: holes when large.
  cv::Mat clear_inside(h, w, CV_8U);
  size_t subject_area = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool in_subject = !(below_core.at<uint8_t>(y, x) && outside[labels.at<int>(y, x)]);
      subject_area += in_subject;
      clear_inside.at<uint8_t>(y, x) = in_subject && alpha.at(x, y, 0) <= kSolidMatteClear;
    }
  cv::Mat clear_labels, stats, centroids;
  const int clear_count = cv::connectedComponentsWithStats(clear_inside, clear_labels, stats, centroids, 4, CV_32S);
  std::vector<char> hole(size_t(clear_count), 0);
  for (int i = 1; i < clear_count; ++i)
    hole[size_t(i)] = double(stats.at<int>(i, cv::CC_STAT_AREA)) >= kSolidMatteMinHole * double(subject_area);
  // Open pixels (the outside and the holes) are 0 here, for their distance transform.
  cv::Mat closed(h, w, CV_8U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool open = (below_core.at<uint8_t>(y, x) && outside[labels.at<int>(y, x)]) ||
                        hole[size_t(clear_labels.at<int>(y, x))];
      closed.at<uint8_t>(y, x) = open ? 0 : 1;
    }
  cv::Mat to_open;
  cv::distanceTransform(closed, to_open, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  const float radius = std::max(1.f, float(std::max(w, h)) / 256.f);
  Image out = alpha;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float floor = std::clamp(to_open.at<float>(y, x) / radius - 1.f, 0.f, 1.f);
      out.at(x, y, 0) = std::max(out.at(x, y, 0), floor);
    }
  return out;
}

}  // namespace u3d
