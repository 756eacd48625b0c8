#pragma once
// PNG decoding through libpng with the project's own error and warning handlers. OpenCV's PNG decoder
// leaves libpng's default handlers in place, which print "libpng error: ..." and "libpng warning: ..."
// lines of their own on stderr; here a libpng error becomes the Error's reason and a warning a
// "warning:" progress line naming the image (core/progress.h). load_image and decode_image read every
// PNG with it, and other formats (JPEG) with OpenCV.
#include <cstddef>
#include <string>

#include "core/image.h"

namespace u3d {

// True when the bytes start with the 8-byte PNG signature.
bool is_png_signature(const unsigned char* bytes, size_t size);

// Decodes PNG bytes as OpenCV's IMREAD_UNCHANGED keeps them, in RGB(A) order, scaled to [0, 1] from 8
// or 16 bits: gray stays 1 channel (a transparency chunk is ignored), gray with alpha becomes RGBA, a
// palette or RGB image becomes RGBA when it has a transparency chunk (tRNS) and RGB otherwise; gray
// below 8 bits is expanded. Images over 2^30 pixels are refused as OpenCV refuses them. `what` names
// the source in errors and warnings.
Image decode_png(const unsigned char* bytes, size_t size, const std::string& what);

}  // namespace u3d
