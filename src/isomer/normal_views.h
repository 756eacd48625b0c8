#pragma once
// What the optimisation stages fit: each view's world-space normal map, encoded as (n + 1) / 2 with the
// mask as alpha, and its camera; at the input resolution or brought down to a stage's working
// resolution (the coarse stage fits edges of 0.02 or longer, a few pixels at 256 px, and costs a
// quarter as much there).
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/view_set.h"

namespace u3d {

struct NormalViews {
  std::vector<Image> normal_maps;  // RGBA: RGB = (n + 1) / 2 in world space, alpha = mask
  std::vector<Camera> cameras;     // one per map, of the map's size
};

// The view set's normal maps, encoded, with the canonical cameras at their resolution.
NormalViews normal_views(const ViewSet& views);

// Checks that there is one map per camera, of its camera's size and RGBA; `what` names the caller in
// the Error ("coarse stage").
void check_normal_views(const NormalViews& views, const std::string& what);

// The views with their longer side at most max_resolution (0 = unchanged). Colour is averaged with
// alpha weights so the background colour does not bleed into the object's rim.
NormalViews at_resolution(const NormalViews& views, int max_resolution);

}  // namespace u3d
