#pragma once
// PNG and JPEG decoding through libpng and libjpeg with the project's own error and warning handlers.
// OpenCV's decoders leave the libraries' default handlers in place, which print lines of their own on
// stderr ("libpng warning: iCCP: known incorrect sRGB profile", "Corrupt JPEG data: premature end of
// data segment"); here a library error becomes the Error's reason and a warning a "warning:" progress
// line naming the image (core/progress.h). PNG and JPEG are the only image formats read: anything else is
// refused by its content, which also keeps the other decoders OpenCV carries (GDAL, OpenJPEG, GDCM, with
// their own stderr lines and, for GDCM, aborts on corrupt input) away from user files. The pixels are
// what OpenCV's IMREAD_UNCHANGED gave before: the same library settings and channel counts, scaled to
// [0, 1] as load_image scaled OpenCV's images, in RGB(A) order.
#include <cstddef>
#include <string>

#include "core/image.h"

namespace u3d {

// True when the bytes start with the 8-byte PNG signature.
bool is_png_signature(const unsigned char* bytes, size_t size);

// True when the bytes start with a JPEG start-of-image marker (FF D8 FF).
bool is_jpeg_signature(const unsigned char* bytes, size_t size);

// Decodes PNG bytes, 8 or 16 bits: gray stays 1 channel (a transparency chunk is ignored), gray with
// alpha becomes RGBA, a palette or RGB image becomes RGBA when it has a transparency chunk (tRNS) and
// RGB otherwise; gray below 8 bits is expanded. Images over 2^30 pixels are refused as OpenCV refuses
// them. `what` names the source in errors and warnings.
Image decode_png(const unsigned char* bytes, size_t size, const std::string& what);

// Decodes JPEG bytes: gray stays 1 channel, colour (YCbCr, RGB, CMYK, YCCK) becomes RGB. A file that
// ends early decodes with a warning, as libjpeg fills the rest in. Images over 2^30 pixels are refused.
Image decode_jpeg(const unsigned char* bytes, size_t size, const std::string& what);

// The width and height a PNG (its IHDR chunk) or a JPEG (its first start-of-frame segment) states, read
// without decoding anything else, so that a caller can refuse an image too large to decode before its
// pixels are allocated. An Error naming `what` when the bytes are neither or the header is cut short.
struct ImageSize {
  int width = 0;
  int height = 0;
};
ImageSize peek_image_size(const unsigned char* bytes, size_t size, const std::string& what);

// Decodes PNG or JPEG bytes, told apart by their signature (load_image for files, the glTF reader for
// embedded textures). Anything else is an Error "cannot decode <what>: not a PNG or JPEG image".
Image decode_image(const unsigned char* bytes, size_t size, const std::string& what);

}  // namespace u3d
