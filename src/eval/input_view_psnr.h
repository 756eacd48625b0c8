#pragma once
// How closely a coloured reconstruction reproduces the views it was made from (issue 40): the mesh
// rendered with its own colours (texture or vertex colours, unlit, as appearance.h renders) through
// each input view's camera at that view's RGB resolution, compared with the view's RGB image over the
// view's mask. The 24 turntable renders of appearance.h (256 px by default) are coarser than a 2048
// texture; these renders have the input views' resolution (2048 px in the pipeline, where the views
// are upscaled x4), so they see whether a texture keeps the views' detail.
//
// Per view: the mesh is rendered at ssaa x the view's resolution and box-filtered down (colour
// weighted by coverage, as the views `unique3d render` writes), textures sampled bilinearly without
// mipmaps (the ssaa^2 samples of a pixel, each bilinear, spread over its footprint: a 2048 texture
// holds at most about two texels a pixel of a 512 px view with ssaa 2). Render and view are composited
// on white by their alpha, and
//   PSNR = 10 log10(1 / MSE), MSE over the pixels of the view's mask (RGB alpha >= 0.5) and the R, G, B
//   channels of the sRGB values in [0, 1], capped at kPsnrCapDb.
// Mask pixels the mesh leaves uncovered count (white against the view's colour); pixels off the mask
// do not. The mesh must be in the views' frame (what `reconstruct` writes unless asked for the
// official output scale).
#include <array>

#include "core/mesh.h"
#include "core/view_set.h"

namespace u3d {

struct InputViewPsnr {
  int ssaa = 0;
  std::array<double, 4> views{};         // PSNR (dB) per view, indexed by int(View)
  std::array<size_t, 4> mask_pixels{};  // the pixels each view's PSNR is taken over
  double mean = 0;                       // mean of the four
};

// Throws Error when ssaa is outside [1, 8] or a view's mask is empty.
InputViewPsnr input_view_psnr(const Mesh& mesh, const ViewSet& views, int ssaa);

}  // namespace u3d
