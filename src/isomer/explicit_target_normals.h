#pragma once
// ExplicitTarget normals (paper Sec. ISOMER, "ExplicitTarget"): for every vertex, one target normal
// fused from all views that see it, instead of one target per view. Fusing first removes the
// disagreement between inconsistent views that would otherwise pull the surface back and forth
// (the "wave" artefacts of a plain multi-view loss).
//
// As the official multiview projection: a view contributes to the vertices of its visible faces that
// face it (normal . toward_camera > facing_epsilon); the contribution is the bilinearly sampled map
// colour weighted by view_weight * |cos(vertex normal, view)| * map alpha; vertices whose total weight
// stays at or below confidence_threshold keep their current normal.
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "render/rasterizer.h"

namespace u3d {

struct ExplicitTargetOptions {
  std::vector<float> view_weights = {2.0f, 0.8f, 1.0f, 0.8f};  // front, right, back, left
  float confidence_threshold = 0.1f;
  float facing_epsilon = 0.05f;
};

struct ExplicitTargetNormals {
  std::vector<Vec3f> normals;  // unit target normal per vertex
  // How much the views that see a vertex disagree about its normal: the weighted RMS distance of
  // their sampled normals from the weighted mean (about the angle in radians for small spreads);
  // 0 where one view or none contributes.
  std::vector<float> disagreement;
};

// rasters[i]: the mesh rasterized from cameras[i] (visibility). normal_maps: RGBA, RGB = (n + 1) / 2
// world space, alpha = mask, not premultiplied.
ExplicitTargetNormals explicit_target_normals(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& faces,
                                           const std::vector<Vec3f>& vertex_normals,
                                           const std::vector<Image>& normal_maps, const std::vector<Camera>& cameras,
                                           const std::vector<const RasterBuffer*>& rasters,
                                           const ExplicitTargetOptions& options = {});

// Bilinear RGBA sample at continuous pixel coordinates (centres at +0.5), clamped at the border.
Vec4f sample_bilinear(const Image& image, float x, float y);

}  // namespace u3d
