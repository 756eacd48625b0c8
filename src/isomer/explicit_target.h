#pragma once
// ExplicitTarget (paper Sec. 3.2 and appendix): one target value per vertex, the weighted mean of
// what the views that see the vertex say about it, here for colouring (values = RGB images). The
// refinement stage's variant for normals is explicit_target_normals.h (ExplicitTargetOptions).
//
// For view i and vertex v (official `multiview_color_projection`, docs/official_reference.md 4.2):
//   - visibility: v belongs to a face that owns at least one pixel of the view's rasterization and
//     whose face normal faces the camera, cos(n_face, toward camera) > facing_epsilon;
//   - value: the view image sampled bilinearly at v's projection (pixel centres at +0.5, clamped at
//     the border), RGB clamped to [0, 1], alpha a;
//   - weight: view_weight[i] * |cos(n_v, toward camera)|^cos_power * a, with n_v the area-weighted
//     vertex normal.
// The paper writes the weight as cos^2 (cos_power 2); the official refinement uses |cos| (1).
#include <array>
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "core/mesh.h"
#include "core/view_set.h"

namespace u3d {

// Named apart from explicit_target_normals.h's ExplicitTargetOptions: one name for two structs would
// break the one-definition rule inside u3d_isomer.
struct ColorTargetOptions {
  std::array<float, 4> view_weights{2.0f, 0.2f, 1.0f, 0.2f};  // front, right, back, left (official colouring)
  int cos_power = 2;
  float facing_epsilon = 0.05f;
  int raster_resolution = 1024;  // official visibility raster
};

struct ExplicitTarget {
  std::vector<Vec3f> weighted_sum;  // sum of weight * value per vertex
  std::vector<float> weight;        // total weight per vertex (0 = seen by no view)

  Vec3f mean(size_t v) const { return weight[v] > 0 ? Vec3f(weighted_sum[v] / weight[v]) : Vec3f(0, 0, 0); }
};

// Vertices of `mesh` visible in view v by the rule above (nonzero = visible).
std::vector<uint8_t> visible_vertices(const Mesh& mesh, const std::vector<Vec3f>& face_normals, View v,
                                      const ColorTargetOptions& options);

// images[i]: RGBA view images (any square resolution), indexed by int(View).
ExplicitTarget compute_explicit_target(const Mesh& mesh, const std::array<const Image*, 4>& images,
                                       const ColorTargetOptions& options = {});

// Final colouring (official: threshold 0.2, "smooth" below it, then completion of the rest).
struct ColoringOptions {
  ColorTargetOptions target;
  float confidence_threshold = 0.2f;  // vertices with less total weight are filled by completion
  int mask_erosion_px = 1;            // official erodes the colour masks by 1 px (3x3)
  Vec3f fallback_color{0.5f, 0.5f, 0.5f};  // only for parts no colour can reach
};

struct ColoringReport {
  size_t confident = 0;    // vertices coloured from the views
  size_t completed = 0;    // vertices coloured by completion
  size_t unreachable = 0;  // vertices left with the (blended) fallback colour
};

// Sets mesh.colors (sRGB) from the views' RGB images.
ColoringReport color_mesh(Mesh& mesh, const ViewSet& views, const ColoringOptions& options = {});

}  // namespace u3d
