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
// holds at most about two texels a pixel of a 512 px view with ssaa 2). Then
//   PSNR = 10 log10(1 / MSE), MSE over the pixels in both the view's mask (RGB alpha >= 0.5) and the
//   render's (coverage >= 0.5) and the R, G, B channels of their straight (not composited) sRGB
//   values in [0, 1], capped at kPsnrCapDb; 0 dB for a view with no such pixel.
// Only where both show the object is colour compared: mask pixels the mesh leaves uncovered are a
// geometry error (mask_agreement.h counts them), and composited on white they outweigh the texture:
// on avocado at 2048 px, the 0.4 % of mask pixels that render or view covers only in part held 85 %
// of the squared error over the whole mask.
// The mesh must be in the views' frame (what `reconstruct` writes unless asked for the official
// output scale).
#include <array>

#include "core/mesh.h"
#include "core/view_set.h"

namespace u3d {

struct InputViewPsnr {
  int ssaa = 0;
  std::array<double, 4> views{};   // PSNR (dB) per view, indexed by int(View)
  std::array<size_t, 4> pixels{};  // the pixels each view's PSNR is taken over (in both masks)
  double mean = 0;                 // mean of the four
};

// Throws Error when ssaa is outside [1, 8].
InputViewPsnr input_view_psnr(const Mesh& mesh, const ViewSet& views, int ssaa);

}  // namespace u3d
