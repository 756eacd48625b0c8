#pragma once
// Anti-aliasing by supersampling: render at k times the resolution, then average k x k blocks.
#include "core/image.h"

namespace u3d {

// Box-filters an RGBA image (straight alpha) down by `factor` in each direction. Colours are averaged
// weighted by alpha, so silhouette pixels keep the object's colour instead of darkening toward the
// background; alpha becomes the covered fraction. Width and height must be multiples of factor.
Image downsample_alpha_weighted(const Image& rgba, int factor);

}  // namespace u3d
