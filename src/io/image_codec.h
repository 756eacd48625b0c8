#pragma once
// Textures embedded in mesh files (GLB) travel as encoded PNG/JPEG bytes, not as files: encoding them
// here, decoding with core's decode_image (core/image_decode.h).
#include <cstddef>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/image_decode.h"  // decode_image, for the embedded textures

namespace u3d {

// 8-bit PNG of a 1/3/4-channel image, values clamped to [0, 1]. Throws Error on NaN.
std::vector<unsigned char> encode_png(const Image& image, const std::string& what);

// How mesh writers store textures: lossless PNG, or JPEG (quality 95, alpha dropped), about a fifth
// of the bytes for a baked colour texture.
enum class TextureFormat { Png, Jpeg };

// Parses "png" / "jpg" / "jpeg"; throws Error otherwise.
TextureFormat parse_texture_format(const std::string& text);
const char* texture_extension(TextureFormat format);  // ".png" or ".jpg"
const char* texture_mime_type(TextureFormat format);  // "image/png" or "image/jpeg"

// Encoded bytes of an 8-bit image in `format` (as encode_png; JPEG drops alpha).
std::vector<unsigned char> encode_image(const Image& image, TextureFormat format, const std::string& what);

}  // namespace u3d
