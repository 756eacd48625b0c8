#pragma once
// Working resolution of a stage: normal maps and their cameras brought to a lower resolution (the
// coarse stage fits edges of 0.02 or longer, a few pixels at 256 px, and costs a quarter as much there).
#include <vector>

#include "core/camera.h"
#include "core/image.h"

namespace u3d {

struct ViewsAtResolution {
  std::vector<Image> normal_maps;
  std::vector<Camera> cameras;
};

// Views whose longer side is at most max_resolution (0 = unchanged). Colour is averaged with alpha
// weights so the background colour does not bleed into the object's rim.
ViewsAtResolution views_at_resolution(const std::vector<Image>& normal_maps, const std::vector<Camera>& cameras,
                                      int max_resolution);

}  // namespace u3d
