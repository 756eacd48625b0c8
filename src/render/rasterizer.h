#pragma once
// The rasterize primitive (as nvdiffrast's `rasterize`): for each pixel, which triangle covers its
// centre, where (barycentrics) and how far (depth). Everything else (normals, colours, textures,
// anti-aliasing, gradients) is computed from this buffer by the other files of render/.
//
// Coverage rule: a pixel belongs to a triangle when its centre (x+0.5, y+0.5) lies inside it, with a
// top-left fill rule for centres exactly on an edge, so triangles sharing an edge never both cover (or
// both miss) a pixel. Depth test: nearest camera-space depth wins; ties go to the lower face id.
// Both orientations are rasterized (no back-face culling) unless RasterOptions::cull_backfaces.
#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "core/mesh.h"

namespace u3d {

struct RasterOptions {
  bool cull_backfaces = false;
};

// Inclusive pixel rectangle; empty when x0 > x1.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool empty() const { return x0 > x1 || y0 > y1; }
};

struct RasterBuffer {
  int width = 0;
  int height = 0;
  // Every covered pixel lies inside this rectangle (the union of the drawn triangles' pixel ranges):
  // later passes scan only it, and rasterize_into resets only it.
  PixelRect footprint;
  std::vector<int32_t> face_id;  // per pixel; -1 = background
  std::vector<Vec2f> bary;       // per pixel (b1, b2) of face vertices 1 and 2; b0 = 1 - b1 - b2;
                                 // perspective-correct, i.e. barycentrics of the 3D surface point
  std::vector<float> depth;      // per pixel camera-space depth (positive in front); +inf = background

  bool covered(size_t pixel) const { return face_id[pixel] >= 0; }
  size_t pixel_count() const { return size_t(width) * size_t(height); }
};

RasterBuffer rasterize(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, const Camera& camera,
                       const RasterOptions& options = {});

// The same into an existing buffer, for frame-by-frame rendering: when `buf` has the camera's size its
// storage is reused and only its previous footprint is reset, so the cost follows the object's size
// on screen rather than the image's.
void rasterize_into(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, const Camera& camera,
                    RasterBuffer& buf, const RasterOptions& options = {});

inline RasterBuffer rasterize(const Mesh& mesh, const Camera& camera, const RasterOptions& options = {}) {
  return rasterize(mesh.positions, mesh.faces, camera, options);
}

}  // namespace u3d
