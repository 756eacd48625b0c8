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

struct RasterBuffer {
  int width = 0;
  int height = 0;
  std::vector<int32_t> face_id;  // per pixel; -1 = background
  std::vector<Vec2f> bary;       // per pixel (b1, b2) of face vertices 1 and 2; b0 = 1 - b1 - b2;
                                 // perspective-correct, i.e. barycentrics of the 3D surface point
  std::vector<float> depth;      // per pixel camera-space depth (positive in front); +inf = background

  bool covered(size_t pixel) const { return face_id[pixel] >= 0; }
  size_t pixel_count() const { return size_t(width) * size_t(height); }
};

RasterBuffer rasterize(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces, const Camera& camera,
                       const RasterOptions& options = {});

inline RasterBuffer rasterize(const Mesh& mesh, const Camera& camera, const RasterOptions& options = {}) {
  return rasterize(mesh.positions, mesh.faces, camera, options);
}

}  // namespace u3d
