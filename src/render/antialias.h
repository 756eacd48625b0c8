#pragma once
// The antialias primitive (Laine et al. 2020, nvdiffrast's `antialias`): analytic anti-aliasing of
// silhouette edges. For every pair of horizontally or vertically adjacent pixels showing different
// triangles, the nearer triangle's silhouette edge crossing the segment between the two pixel centres
// is found; the pixel on the far side of the crossing point (as seen from the midpoint) is blended
// toward its neighbour in proportion to how far the edge sits from the midpoint. Because the blend
// weight depends continuously on the projected edge, the backward pass gives gradients w.r.t. the
// edge's vertex positions: this is what lets the silhouette (and the mask loss) move the mesh.
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "geometry/edge_topology.h"
#include "render/rasterizer.h"
#include "render/screen_projection.h"

namespace u3d {

// For face f and corner i: the vertex across the edge opposite corner i (the third vertex of the
// neighbouring face sharing that edge with opposite orientation), or -1 on a border. Border edges
// always count as silhouettes. Read off the edge topology of `faces` (on an edge with more than two
// faces, the one edge_sides keeps in the other direction).
struct EdgeNeighbors {
  std::vector<Vec3i> opposite;
};
EdgeNeighbors edge_neighbors(const std::vector<Vec3i>& faces, const EdgeTopology& topology);

// One blended pixel pair, recorded by the forward pass for the backward pass.
struct AntialiasPair {
  int32_t pixel0 = 0;  // left / upper pixel
  int32_t pixel1 = 0;  // right / lower neighbour
  int32_t face = 0;    // triangle whose edge was found
  int8_t edge = 0;     // the edge opposite this corner of `face`
  bool down = false;   // vertical pair
  bool from_pixel1 = false;  // `face` is the one shown in pixel1
  float alpha = 0.f;   // signed blend weight: > 0 changes pixel0, < 0 changes pixel1
};

// Finds the silhouette pixel pairs of one rendered view and their blend weights.
std::vector<AntialiasPair> find_antialias_pairs(const RasterBuffer& raster, const std::vector<Vec3i>& faces,
                                                const EdgeNeighbors& neighbors, const ScreenProjection& projection);
// The same into `pairs`, reusing its storage (for frame-by-frame rendering).
void find_antialias_pairs(const RasterBuffer& raster, const std::vector<Vec3i>& faces, const EdgeNeighbors& neighbors,
                          const ScreenProjection& projection, std::vector<AntialiasPair>& pairs);

// Forward: out += blend deltas computed from `color`. `out` must hold a copy of `color` on entry and
// must be a different image (the deltas read unblended colours).
void apply_antialias(const std::vector<AntialiasPair>& pairs, const Image& color, Image& out);

// Backward: with grad_color holding a copy of grad_out on entry (the identity part), adds the blend
// part to grad_color and the silhouette-edge motion part to `screen` (dL/d pixel xy per vertex).
void antialias_backward(const std::vector<AntialiasPair>& pairs, const Image& color, const std::vector<Vec3i>& faces,
                        const ScreenProjection& projection, const Image& grad_out, Image& grad_color,
                        ScreenGradient& screen);

}  // namespace u3d
