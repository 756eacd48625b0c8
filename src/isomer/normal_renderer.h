#pragma once
// Differentiable normal-map renderer of ISOMER (the official NormalsRenderer on the CPU): for each view,
// rasterize, interpolate colour (n + 1) / 2 and coverage alpha, then anti-alias silhouettes. The
// backward pass sends image-space gradients to vertex positions along all three official paths:
// through the vertex normals, through the barycentrics, and through the silhouette edges.
//
// Back faces are culled: the surface is closed and oriented outward, so a back face is always hidden
// behind a front face and culling changes no pixel; it halves the rasterizer's work. (Where a fold
// makes the surface cross itself the visible side differs, but such faces carry no valid normal.)
//
// Only the object's footprint is touched: covered pixels plus the background pixels anti-aliasing
// blends into ("active" pixels). Everywhere else the image is zero and stays zero between frames.
#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "isomer/vertex_normals_grad.h"
#include "render/antialias.h"
#include "render/rasterizer.h"
#include "render/screen_projection.h"

namespace u3d {

struct DifferentiableView {
  Camera camera;
  RasterBuffer raster;
  ScreenProjection projection;
  std::vector<int32_t> covered;        // pixels a triangle covers
  std::vector<int32_t> active;         // covered + background pixels changed by anti-aliasing
  std::vector<AntialiasPair> pairs;    // silhouette pixel pairs
  size_t opaque_pixels = 0;            // active pixels with alpha > 0.5 (the mask of the normal loss)
  Image color;                         // RGBA before anti-aliasing (zero on background)
  Image image;                         // RGBA after anti-aliasing: what the losses see
  Image grad_image;                    // dL/d(image); losses fill it on `active` pixels
  // Scratch for the backward pass.
  Image grad_color;
  std::vector<Vec2f> grad_bary;
  std::vector<float> grad_attributes;
  ScreenGradient screen_grad;
  std::vector<uint8_t> listed;    // per pixel, while collecting the pixels blends change
  std::vector<int32_t> blended;   // those pixels, each once
  std::vector<Vec3f> grad_positions;
};

class NormalRenderer {
 public:
  explicit NormalRenderer(std::vector<Camera> cameras);

  size_t view_count() const { return views_.size(); }
  const DifferentiableView& view(size_t i) const { return views_[i]; }
  DifferentiableView& view(size_t i) { return views_[i]; }

  // View indices by decreasing footprint in the last frame. Per-view parallel loops hand out views in
  // this order: two threads taking the two large side views first end together, where the plain order
  // (small, large, small, large) leaves one idle for a small view's time every pass.
  const std::vector<int>& largest_first() const { return largest_first_; }

  // Renders all views of the mesh with these unit vertex normals; clears each view's grad_image (zero
  // everywhere afterwards, as long as only the active pixels were written since the last render).
  // `topology` is the edge topology of `faces` (the anti-aliasing finds silhouette edges on it).
  void render(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, const EdgeTopology& topology,
              const std::vector<Vec3f>& vertex_normals);

  // Renders other per-vertex unit vectors with the current views' rasters and anti-aliasing (no
  // gradient): the refinement stage's target images. `out` gets full-size RGBA images.
  void render_attribute(const std::vector<Vec3i>& faces, const std::vector<Vec3f>& unit_vectors, size_t view_index,
                        Image& out);

  // Adds dL/d(positions) for the views' grad_image (set on active pixels by the losses).
  void backward(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, const VertexNormals& normals,
                std::vector<Vec3f>& grad_positions);

 private:
  std::vector<DifferentiableView> views_;
  std::vector<float> attributes_;  // per vertex ((n + 1) / 2, 1)
  EdgeNeighbors neighbors_;
  Image attribute_color_;  // render_attribute's colour before anti-aliasing
  std::vector<int> largest_first_;
};

// ((n + 1) / 2, 1) per vertex: the colour and coverage channels the renderer interpolates.
std::vector<float> normal_color_attributes(const std::vector<Vec3f>& unit_vectors);

}  // namespace u3d
