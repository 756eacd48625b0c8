#pragma once
// F-score at a distance threshold (Knapitsch et al. 2017, "Tanks and Temples"): the harmonic mean of
// precision (share of predicted surface samples within the threshold of the GT surface) and recall
// (share of GT samples within the threshold of the predicted surface).
#include "eval/chamfer.h"

namespace u3d {

struct FScore {
  float threshold = 0;
  double precision = 0;
  double recall = 0;
  double fscore = 0;  // 0 when precision + recall is 0
};

FScore fscore(const SurfaceDistances& d, float threshold);

}  // namespace u3d
