#include "core/image_decode.h"

#include <cstdio>  // before jpeglib.h, which needs size_t and FILE declared

#include <jpeglib.h>
#include <png.h>

#include <bit>
#include <csetjmp>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/error.h"
#include "core/progress.h"

namespace u3d {

static_assert(std::endian::native == std::endian::little, "16-bit samples are byte-swapped for a little-endian host");

namespace {

// 8-bit samples to [0, 1] as load_image scaled OpenCV's images: the sample times this float.
constexpr float k8BitScale = float(1.0 / 255.0);

// A decoder's warnings as progress lines naming the image, then its error, if it failed, as the Error.
void report(bool ok, const std::vector<std::string>& warnings, const std::string& error, const std::string& what) {
  for (const std::string& warning : warnings) progress("warning: " + what + ": " + warning);
  if (!ok) throw Error("cannot decode " + what + ": " + error);
}

// Everything the libpng callbacks touch, and everything that must survive a longjmp back to the
// setjmp in decode_png: libpng's error path jumps over the frames between, so no C++ object may live
// in them, and locals modified after setjmp would be indeterminate after the jump.
struct PngRead {
  const unsigned char* bytes = nullptr;
  size_t size = 0;
  size_t offset = 0;
  std::string error;                  // libpng's reason, set before it jumps back
  std::vector<std::string> warnings;  // reported once decoding ends
  std::vector<unsigned char> pixels;
  std::vector<png_bytep> rows;
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngRead() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

void on_error(png_structp png, png_const_charp message) {
  auto* read = static_cast<PngRead*>(png_get_error_ptr(png));
  read->error = message ? message : "unknown libpng error";
  png_longjmp(png, 1);
}

void on_warning(png_structp png, png_const_charp message) {
  auto* read = static_cast<PngRead*>(png_get_error_ptr(png));
  if (read->warnings.size() < 8) read->warnings.emplace_back(message ? message : "unknown libpng warning");
}

void on_read(png_structp png, png_bytep out, png_size_t count) {
  auto* read = static_cast<PngRead*>(png_get_io_ptr(png));
  if (count > read->size - read->offset) png_error(png, "the data ends early (truncated file)");
  std::memcpy(out, read->bytes + read->offset, count);
  read->offset += count;
}

// The libpng calls, between setjmp and the end of reading. Returns false when libpng jumped back with
// an error (in read.error). Nothing here has a destructor: all state is in `read`.
bool read_pixels(PngRead& read, int& width, int& height, int& channels, int& depth) {
  if (setjmp(png_jmpbuf(read.png))) return false;
  png_set_read_fn(read.png, &read, on_read);
  png_read_info(read.png, read.info);
  const png_uint_32 w = png_get_image_width(read.png, read.info), h = png_get_image_height(read.png, read.info);
  const int color_type = png_get_color_type(read.png, read.info);
  const int bit_depth = png_get_bit_depth(read.png, read.info);
  if (uint64_t(w) * h > (uint64_t(1) << 30)) {
    read.error = "larger than the 2^30 pixels an image may have";
    return false;
  }
  const bool has_trns = png_get_valid(read.png, read.info, PNG_INFO_tRNS) != 0;
  // OpenCV's channel counts for IMREAD_UNCHANGED.
  switch (color_type) {
    case PNG_COLOR_TYPE_GRAY: channels = 1; break;
    case PNG_COLOR_TYPE_GRAY_ALPHA:
    case PNG_COLOR_TYPE_RGB_ALPHA: channels = 4; break;
    default: channels = has_trns ? 4 : 3; break;  // RGB, palette
  }
  depth = bit_depth == 16 ? 16 : 8;
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(read.png);
  if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(read.png);
  if (channels == 4 && has_trns) png_set_tRNS_to_alpha(read.png);
  if (color_type == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(read.png);
  if (depth == 16) png_set_swap(read.png);  // PNG stores big-endian samples; the host is little-endian
  png_set_interlace_handling(read.png);
  png_read_update_info(read.png, read.info);
  const size_t row_bytes = png_get_rowbytes(read.png, read.info);
  if (row_bytes != size_t(w) * size_t(channels) * size_t(depth / 8)) {
    read.error = "unexpected row size after the colour conversions";
    return false;
  }
  read.pixels.resize(row_bytes * h);
  read.rows.resize(h);
  for (png_uint_32 y = 0; y < h; ++y) read.rows[y] = read.pixels.data() + size_t(y) * row_bytes;
  png_read_image(read.png, read.rows.data());
  png_read_end(read.png, nullptr);
  width = int(w);
  height = int(h);
  return true;
}

}  // namespace

bool is_png_signature(const unsigned char* bytes, size_t size) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return size >= 8 && std::memcmp(bytes, kSignature, 8) == 0;
}

Image decode_png(const unsigned char* bytes, size_t size, const std::string& what) {
  PngRead read;
  read.bytes = bytes;
  read.size = size;
  read.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &read, on_error, on_warning);
  if (read.png) read.info = png_create_info_struct(read.png);
  require(read.png && read.info, "cannot decode " + what + ": out of memory");
  int width = 0, height = 0, channels = 0, depth = 0;
  const bool ok = read_pixels(read, width, height, channels, depth);
  report(ok, read.warnings, read.error, what);

  Image image(width, height, channels);
  if (depth == 16) {
    const float scale = float(1.0 / 65535.0);  // as load_image scaled OpenCV's 16-bit images
    for (size_t i = 0; i < image.data.size(); ++i) {
      uint16_t sample;
      std::memcpy(&sample, read.pixels.data() + 2 * i, 2);
      image.data[i] = float(sample) * scale;
    }
  } else {
    for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = float(read.pixels[i]) * k8BitScale;
  }
  return image;
}

namespace {

// As PngRead, for libjpeg: its error handler longjmps back to read_jpeg_pixels.
struct JpegRead {
  jpeg_decompress_struct info{};
  jpeg_error_mgr errors{};
  std::jmp_buf jump;
  bool created = false;
  std::string error;
  std::vector<std::string> warnings;
  std::vector<unsigned char> pixels;
  ~JpegRead() {
    if (created) jpeg_destroy_decompress(&info);
  }
};

std::string jpeg_message(j_common_ptr info) {
  char text[JMSG_LENGTH_MAX] = {};
  info->err->format_message(info, text);
  return text;
}

void on_jpeg_error(j_common_ptr info) {
  auto* read = static_cast<JpegRead*>(info->client_data);
  read->error = jpeg_message(info);
  std::longjmp(read->jump, 1);
}

// libjpeg's default emit_message passes the first warning (and trace messages, which are off) here.
void on_jpeg_message(j_common_ptr info) {
  auto* read = static_cast<JpegRead*>(info->client_data);
  if (read->warnings.size() < 8) read->warnings.push_back(jpeg_message(info));
}

bool read_jpeg_pixels(JpegRead& read, const unsigned char* bytes, size_t size, int& width, int& height, int& channels) {
  if (setjmp(read.jump)) return false;
  read.info.err = jpeg_std_error(&read.errors);
  read.errors.error_exit = on_jpeg_error;
  read.errors.output_message = on_jpeg_message;
  read.info.client_data = &read;
  jpeg_create_decompress(&read.info);
  read.created = true;
  jpeg_mem_src(&read.info, bytes, static_cast<unsigned long>(size));
  jpeg_read_header(&read.info, TRUE);
  if (uint64_t(read.info.image_width) * read.info.image_height > (uint64_t(1) << 30)) {
    read.error = "larger than the 2^30 pixels an image may have";
    return false;
  }
  // As OpenCV: gray stays gray, four components (CMYK, YCCK) come out as CMYK and are converted below,
  // everything else as RGB.
  const bool four = read.info.num_components == 4;
  read.info.out_color_space = four ? JCS_CMYK : read.info.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(&read.info);
  const size_t stride = size_t(read.info.output_width) * size_t(read.info.output_components);
  read.pixels.resize(stride * read.info.output_height);
  while (read.info.output_scanline < read.info.output_height) {
    JSAMPROW row = read.pixels.data() + size_t(read.info.output_scanline) * stride;
    jpeg_read_scanlines(&read.info, &row, 1);
  }
  jpeg_finish_decompress(&read.info);
  width = int(read.info.output_width);
  height = int(read.info.output_height);
  channels = read.info.output_components;
  return true;
}

}  // namespace

bool is_jpeg_signature(const unsigned char* bytes, size_t size) {
  return size >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8 && bytes[2] == 0xff;
}

Image decode_jpeg(const unsigned char* bytes, size_t size, const std::string& what) {
  JpegRead read;
  int width = 0, height = 0, channels = 0;
  const bool ok = read_jpeg_pixels(read, bytes, size, width, height, channels);
  report(ok, read.warnings, read.error, what);
  require(channels == 1 || channels == 3 || channels == 4,
          "cannot decode " + what + ": " + std::to_string(channels) + " colour components");
  Image image(width, height, channels == 1 ? 1 : 3);
  if (channels != 4) {
    for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = float(read.pixels[i]) * k8BitScale;
    return image;
  }
  // Inverted CMYK (what Adobe writes and libjpeg hands out), converted to RGB as OpenCV converts it.
  for (size_t p = 0; p < image.pixel_count(); ++p) {
    const unsigned char* cmyk = read.pixels.data() + p * 4;
    const int k = cmyk[3];
    for (int c = 0; c < 3; ++c) image.data[p * 3 + c] = float(k - ((255 - cmyk[c]) * k >> 8)) * k8BitScale;
  }
  return image;
}

namespace {

uint32_t big_endian(const unsigned char* p, int bytes) {
  uint32_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | p[i];
  return value;
}

// The frame size of a JPEG: its markers are walked segment by segment (each FF xx followed by a 2-byte
// length, standalone markers without one) up to the first start-of-frame (C0-CF but C4, C8 and CC).
ImageSize peek_jpeg_size(const unsigned char* bytes, size_t size, const std::string& what) {
  size_t at = 2;  // after the start-of-image marker
  while (at + 4 <= size) {
    if (bytes[at] != 0xFF) break;
    const unsigned char marker = bytes[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length
      at += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) break;  // end of image, or scan data before any frame
    const size_t length = big_endian(bytes + at + 2, 2);
    if (length < 2) break;
    const bool frame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame) {
      if (at + 9 > size || length < 7) break;
      return {int(big_endian(bytes + at + 7, 2)), int(big_endian(bytes + at + 5, 2))};
    }
    at += 2 + length;
  }
  throw Error("cannot decode " + what + ": its JPEG header ends before the image size");
}

}  // namespace

ImageSize peek_image_size(const unsigned char* bytes, size_t size, const std::string& what) {
  if (is_png_signature(bytes, size)) {
    // Signature (8), then the first chunk, which must be IHDR: length (4), type (4), width (4), height (4).
    require(size >= 24 && std::memcmp(bytes + 12, "IHDR", 4) == 0,
            "cannot decode " + what + ": its PNG header ends before the image size");
    const uint32_t width = big_endian(bytes + 16, 4), height = big_endian(bytes + 20, 4);
    require(width > 0 && height > 0 && width <= 0x7FFFFFFFu && height <= 0x7FFFFFFFu,
            "cannot decode " + what + ": its PNG header states an invalid size");
    return {int(width), int(height)};
  }
  if (is_jpeg_signature(bytes, size)) return peek_jpeg_size(bytes, size, what);
  throw Error("cannot decode " + what + (size == 0 ? ": no data" : ": not a PNG or JPEG image"));
}

Image decode_image(const unsigned char* bytes, size_t size, const std::string& what) {
  if (is_png_signature(bytes, size)) return decode_png(bytes, size, what);
  if (is_jpeg_signature(bytes, size)) return decode_jpeg(bytes, size, what);
  throw Error("cannot decode " + what + (size == 0 ? ": no data" : ": not a PNG or JPEG image"));
}

}  // namespace u3d
