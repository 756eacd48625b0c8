#pragma once
// Preview pictures of a coloured mesh: the four canonical views side by side, and a turntable strip
// (frames every 360/frames degrees of azimuth, slightly from above). Colours are the mesh's, dimmed
// by a headlight term so the shape reads; the background is light gray.
#include "core/image.h"
#include "core/mesh.h"

namespace u3d {

Image preview_four_views(const Mesh& mesh, int resolution = 256);
Image preview_turntable(const Mesh& mesh, int frames = 8, int resolution = 192, float elevation_deg = 20.f);

}  // namespace u3d
