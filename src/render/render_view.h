#pragma once
// One-call reference render of a mesh: colour and normal images of a view, optionally anti-aliased.
#include "core/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "render/shade.h"

namespace u3d {

struct RenderSettings {
  NormalSpace normal_space = NormalSpace::World;
  bool smooth_normals = true;  // interpolated vertex normals; false = face normals
  int ssaa = 1;                // supersampling factor per axis (1 = none)
  bool cull_backfaces = false;
};

struct RenderedView {
  Image rgb;     // RGBA, sRGB colour, alpha = coverage
  Image normal;  // RGBA, (n + 1) / 2, alpha = coverage
};

RenderedView render_view(const Mesh& mesh, const Camera& camera, const RenderSettings& settings = {});

}  // namespace u3d
