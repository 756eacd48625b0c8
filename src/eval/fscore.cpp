#include "eval/fscore.h"

#include <algorithm>

namespace u3d {

namespace {

double share_within(const std::vector<float>& distances, float threshold) {
  if (distances.empty()) return 0;
  auto n = std::count_if(distances.begin(), distances.end(), [&](float d) { return d <= threshold; });
  return double(n) / double(distances.size());
}

}  // namespace

FScore fscore(const SurfaceDistances& d, float threshold) {
  FScore f;
  f.threshold = threshold;
  f.precision = share_within(d.pred_to_gt, threshold);
  f.recall = share_within(d.gt_to_pred, threshold);
  double sum = f.precision + f.recall;
  f.fscore = sum > 0 ? 2 * f.precision * f.recall / sum : 0;
  return f;
}

}  // namespace u3d
