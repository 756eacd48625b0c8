#pragma once
// Images from a RasterBuffer. Every output is RGBA with straight (not premultiplied) colour, alpha = 1
// where a face covers the pixel centre and 0 elsewhere; background pixels are (0, 0, 0, 0).
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "render/rasterizer.h"

namespace u3d {

// Normal map RGB = (n + 1) / 2 from per-vertex normals interpolated with the barycentrics and
// renormalized (faces whose interpolated normal vanishes fall back to their geometric normal).
Image shade_vertex_normals(const RasterBuffer& buf, const std::vector<Vec3f>& positions,
                           const std::vector<Vec3i>& faces, const std::vector<Vec3f>& vertex_normals,
                           const Camera& camera, NormalSpace space);

// Normal map RGB = (n + 1) / 2 from one normal per face (flat shading).
Image shade_face_normals(const RasterBuffer& buf, const std::vector<Vec3f>& face_normals, const Camera& camera,
                         NormalSpace space);

// Surface colour (sRGB): material base colour x texture (via UVs) x vertex colour, whichever the mesh
// has. A mesh with none of them (no vertex colours, no textures, only white base colours) is mid-gray.
Image shade_colors(const RasterBuffer& buf, const Mesh& mesh);

// True when vertex colours, a texture or a non-white base colour give the mesh a colour.
bool has_color_information(const Mesh& mesh);

}  // namespace u3d
