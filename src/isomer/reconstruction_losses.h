#pragma once
// The loss terms of ISOMER's two stages (official recon.py / refine.py), each returning its value and
// adding its gradient: image terms into the renderer's grad_image (sent to positions by
// NormalRenderer::backward), vertex terms straight into grad_positions.
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "isomer/normal_renderer.h"

namespace u3d {

// A view's target as the losses use it: RGBA with colour premultiplied by alpha (background black,
// as the official init_target), plus the pixels the target calls background (alpha < 0.5).
struct NormalTarget {
  Image rgba;
  std::vector<int32_t> background;
  double background_alpha_sq = 0.0;  // sum of target alpha^2 over `background`
};

// From normal maps RGBA (RGB = (n + 1) / 2, alpha = mask, colour not premultiplied).
NormalTarget make_normal_target(const Image& normal_map);

// Mean squared difference over the first `channels` channels of the pixels whose rendered alpha is
// > 0.5 (all views pooled, as the official batch mean), against `references` (one image per view).
double masked_image_l2(NormalRenderer& renderer, const std::vector<const Image*>& references, int channels,
                       float weight);

// Mean squared rendered-minus-target alpha over the target's background pixels (all views pooled).
double background_alpha_l2(NormalRenderer& renderer, const std::vector<NormalTarget>& targets, float weight);

// Expansion regulariser (paper Fig. 5b): 0.5 * mean |sg(p + n) - p|^2, i.e. a constant push of every
// vertex along its normal; inflates thin or collapsed regions the views cannot see.
double expansion_loss(const std::vector<Vec3f>& normals, float weight, std::vector<Vec3f>& grad_positions);

// Penalty for coordinates outside [-limit, limit]: weight * mean(max(|x| - limit, 0)^2) over all
// coordinates. (The official term counts such coordinates, which has no gradient.)
double out_of_box_loss(const std::vector<Vec3f>& positions, float limit, float weight,
                       std::vector<Vec3f>& grad_positions);

}  // namespace u3d
