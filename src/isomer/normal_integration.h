#pragma once
// Normal map -> height map (paper Sec. 3.2, "Initial Mesh Estimation").
//
// A predicted normal field is not integrable, so no single path integral is right. As in the paper,
// the slope field is integrated along straight lines in many directions and the results averaged:
// the map is rotated by `rotations` angles evenly spread over [0, 90) degrees and, for each, summed
// along rows and columns both ways (4 directions per angle, so 4 * rotations directions over 360).
// Every line restarts at zero where it enters the mask, so nothing is integrated across the
// background and the silhouette rim is the height reference.
//
// Two deliberate differences from the official script (docs/official_reference.md):
//   - slopes are the true surface slopes -n_x/n_z, -n_y/n_z (capped at max_slope where n_z -> 0),
//     so an exact normal field gives metric heights; the official script uses 1 - sin(acos(n_x)),
//     which only has the right sign and is rescaled afterwards anyway;
//   - the mean slope over the mask is integrated separately as a plane (remove_mean_slope), because
//     the rim-is-zero reference would otherwise flatten a tilted surface to half its slope.
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace u3d {

struct NormalIntegrationOptions {
  int rotations = 96;             // official target_iteration_count
  float max_slope = 10.f;         // height change per pixel at most (silhouette pixels have n_z ~ 0)
  bool remove_mean_slope = true;  // integrate the mean slope as an exact plane (see above)
};

// normals: camera-space unit normals (x right, y up, z toward the camera), row-major, row 0 at the
// top; mask: nonzero = foreground. Returns heights toward the camera in pixel units (multiply by the
// world size of a pixel for world units), zero outside the mask.
std::vector<float> integrate_normal_map(const std::vector<Vec3f>& normals, const std::vector<uint8_t>& mask, int width,
                                        int height, const NormalIntegrationOptions& options = {});

}  // namespace u3d
