#pragma once
// Texture lookup with the mesh UV convention: UV (0,0) is the bottom-left corner of the texture image,
// whose row 0 is the top. Bilinear between texel centres.
#include "core/image.h"
#include "core/mesh.h"

namespace u3d {

// RGBA at `uv` (gray textures replicate, missing alpha is 1). UVs outside [0,1] wrap around (repeat);
// inside, lookups clamp at the border so the opposite edge of an atlas never bleeds in.
Vec4f sample_texture(const Image& texture, const Vec2f& uv);

}  // namespace u3d
