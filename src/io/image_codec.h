#pragma once
// Textures embedded in mesh files (GLB) travel as encoded PNG/JPEG bytes, not as files.
#include <cstddef>
#include <string>
#include <vector>

#include "core/image.h"

namespace u3d {

// Decodes PNG/JPEG bytes (8/16 bit, gray/RGB/RGBA) like load_image; `what` names the source in errors.
Image decode_image(const unsigned char* bytes, size_t size, const std::string& what);

// 8-bit PNG of a 1/3/4-channel image, values clamped to [0, 1]. Throws Error on NaN.
std::vector<unsigned char> encode_png(const Image& image, const std::string& what);

}  // namespace u3d
