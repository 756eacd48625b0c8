#pragma once
// Texture baking: the colouring of explicit_target.h, per texel instead of per vertex, sampled
// straight from the full-resolution views.
//
// The mesh gets a UV atlas (geometry/uv_atlas.h, axis-aligned charts). Each texel whose centre a
// chart triangle covers is a surface point p with the interpolated vertex normal n; for every view
// that sees p (its face faces the camera by more than facing_epsilon, and p lies on the view's depth
// buffer, rasterized at the colouring's raster_resolution: within `depth_tolerance_px` of its pixels
// of the nearest surface, or on the face the buffer holds there), the view image is sampled
// bilinearly at p's projection with the ExplicitTarget weight
// view_weight * |cos(n, toward camera)|^cos_power * (the colour mask, eroded as for vertices).
// Texels whose total weight w reaches the confidence threshold t take the weighted mean; below it
// they fade, as the official "smooth" rule does for vertices, toward the vertex colouring
// (ExplicitTarget + completion on the mesh, from the views reduced to raster_resolution; it fills
// what no view sees smoothly and without seams): (sum + (t - w) * vertex colour) / t. Texels no
// triangle covers are dilated from their neighbours for gutter + 2 rounds (so bilinear lookups and
// the first mipmaps at chart borders see the chart's own colours), and the rest of the atlas takes
// the mean colour.
#include "core/mesh.h"
#include "core/view_set.h"
#include "geometry/uv_atlas.h"
#include "isomer/explicit_target.h"

namespace u3d {

struct TextureBakeOptions {
  UvAtlasOptions atlas;  // texture size and gutters
  float depth_tolerance_px = 3.f;
};

struct TextureBakeReport {
  ColoringReport vertices;  // the vertex colouring under the threshold
  int charts = 0;
  float texel_efficiency = 0.f;  // texels used: texels_covered over all texels (gutters and padding not counted)
  size_t texels_covered = 0;     // texels whose centre a chart triangle covers: the texels baking fills
  size_t texels_confident = 0;   // of those, texels at or above the threshold
  double uv_seconds = 0.0;       // the atlas
  double bake_seconds = 0.0;     // the rest: texels and dilation, and what of the vertex colouring (beside the atlas) outlasts it
};

// Replaces `mesh` by its atlas mesh (vertices split at chart seams) with UVs and one material whose
// texture (RGB, sRGB, texture_size^2) is baked from the views' RGB images with the colouring's
// weights, masks and threshold; vertex colours are dropped.
TextureBakeReport bake_texture(Mesh& mesh, const ViewSet& views, const ColoringOptions& coloring = {},
                               const TextureBakeOptions& options = {});

}  // namespace u3d
