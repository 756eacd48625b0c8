// The PNG and JPEG decoders (core/image_decode.h) that load_image and decode_image use: the same pixels as
// OpenCV's decoders (for PNG every colour type, bit depth, transparency chunk and interlacing; for JPEG
// gray, colour, progressive, 4:4:4 and CMYK), and the libraries' errors and warnings in the project's
// words instead of their own stderr lines.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>  // before jpeglib.h, which needs size_t and FILE declared

#include <jpeglib.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image.h"
#include "core/image_decode.h"
#include "core/progress.h"
#include "core/temp_dir.h"

namespace fs = std::filesystem;
using namespace u3d;

namespace {

std::string be32(uint32_t v) { return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }

uint32_t crc32(const std::string& bytes) {
  uint32_t c = 0xffffffffu;
  for (unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}

std::string chunk(const std::string& type, const std::string& data) {
  return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
}

// zlib stream of `raw` in stored (uncompressed) deflate blocks.
std::string zlib_stored(const std::string& raw) {
  std::string out("\x78\x01", 2);
  size_t pos = 0;
  do {
    const size_t n = std::min<size_t>(raw.size() - pos, 65535);
    const bool last = pos + n == raw.size();
    out += char(last ? 1 : 0);
    out += {char(n & 0xff), char(n >> 8), char(~n & 0xff), char((~n >> 8) & 0xff)};
    out += raw.substr(pos, n);
    pos += n;
  } while (pos < raw.size());
  uint32_t a = 1, b = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  return out + be32((b << 16) | a);
}

// A PNG of `width` x `height` samples given as one value per sample (bit_depth bits each, packed as PNG
// packs them), filter type 0 on every row; Adam7 order when `interlaced`. `extra` chunks go before IDAT.
std::string make_png(int width, int height, int color_type, int bit_depth, const std::vector<int>& samples,
                     bool interlaced = false, const std::string& extra = "") {
  const int per_pixel = color_type == 0 ? 1 : color_type == 2 ? 3 : color_type == 3 ? 1 : color_type == 4 ? 2 : 4;
  auto row_bytes = [&](const std::vector<int>& row) {
    std::string out(1, '\0');  // filter: none
    int acc = 0, bits = 0;
    for (int v : row) {
      if (bit_depth == 16) {
        out += char(v >> 8);
        out += char(v & 0xff);
        continue;
      }
      acc = (acc << bit_depth) | v;
      bits += bit_depth;
      if (bits == 8) {
        out += char(acc);
        acc = bits = 0;
      }
    }
    if (bits) out += char(acc << (8 - bits));
    return out;
  };
  auto pixel_samples = [&](int x, int y) {
    const auto first = samples.begin() + (size_t(y) * width + x) * per_pixel;
    return std::vector<int>(first, first + per_pixel);
  };
  std::string raw;
  const int passes[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                            {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};  // x0, y0, dx, dy
  for (int p = 0; p < (interlaced ? 7 : 1); ++p) {
    const int x0 = interlaced ? passes[p][0] : 0, y0 = interlaced ? passes[p][1] : 0;
    const int dx = interlaced ? passes[p][2] : 1, dy = interlaced ? passes[p][3] : 1;
    if (x0 >= width) continue;
    for (int y = y0; y < height; y += dy) {
      std::vector<int> row;
      for (int x = x0; x < width; x += dx)
        for (int v : pixel_samples(x, y)) row.push_back(v);
      raw += row_bytes(row);
    }
  }
  const std::string ihdr = be32(uint32_t(width)) + be32(uint32_t(height)) +
                           std::string{char(bit_depth), char(color_type), 0, 0, char(interlaced)};
  return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + extra + chunk("IDAT", zlib_stored(raw)) +
         chunk("IEND", "");
}

// What load_image made of a PNG before it had its own decoder: OpenCV's IMREAD_UNCHANGED, scaled to
// [0, 1] and turned to RGB(A).
Image opencv_decode(const std::string& png) {
  cv::Mat encoded(1, int(png.size()), CV_8U, const_cast<char*>(png.data()));
  cv::Mat m = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
  if (m.empty()) throw Error("OpenCV could not decode it");
  cv::Mat f;
  m.convertTo(f, CV_32F, m.depth() == CV_16U ? 1.0 / 65535.0 : 1.0 / 255.0);
  if (f.channels() == 3) cv::cvtColor(f, f, cv::COLOR_BGR2RGB);
  if (f.channels() == 4) cv::cvtColor(f, f, cv::COLOR_BGRA2RGBA);
  Image image(f.cols, f.rows, f.channels());
  f.copyTo(cv::Mat(f.rows, f.cols, CV_32FC(f.channels()), image.data.data()));
  return image;
}

Image decode(const std::string& png, const std::string& what = "test.png") {
  return decode_png(reinterpret_cast<const unsigned char*>(png.data()), png.size(), what);
}

void expect_same_pixels(const Image& got, const Image& expected) {
  ASSERT_EQ(got.width, expected.width);
  ASSERT_EQ(got.height, expected.height);
  ASSERT_EQ(got.channels, expected.channels);
  for (size_t i = 0; i < got.data.size(); ++i) ASSERT_EQ(got.data[i], expected.data[i]) << "sample " << i;
}

// A JPEG written by libjpeg's compressor, for what OpenCV 4.6 cannot encode: CMYK (written inverted with
// an Adobe marker, as Adobe applications write it; `components` 4) and colour without chroma subsampling
// (`full_chroma`). The samples are a fixed pattern.
std::string libjpeg_encode(int width, int height, int components, bool full_chroma) {
  jpeg_compress_struct info{};
  jpeg_error_mgr errors{};
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  unsigned char* out = nullptr;
  unsigned long out_size = 0;
  jpeg_mem_dest(&info, &out, &out_size);
  info.image_width = JDIMENSION(width);
  info.image_height = JDIMENSION(height);
  info.input_components = components;
  info.in_color_space = components == 4 ? JCS_CMYK : JCS_RGB;
  jpeg_set_defaults(&info);  // CMYK input: CMYK in the file, with the Adobe marker
  if (full_chroma) info.comp_info[0].h_samp_factor = info.comp_info[0].v_samp_factor = 1;
  jpeg_start_compress(&info, TRUE);
  std::vector<unsigned char> row(size_t(width) * size_t(components));
  while (info.next_scanline < info.image_height) {
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < components; ++c)
        row[size_t(x * components + c)] = (unsigned char)((x * 37 + int(info.next_scanline) * 11 + c * 60) % 256);
    JSAMPROW rows[1] = {row.data()};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  std::string bytes(reinterpret_cast<char*>(out), out_size);
  jpeg_destroy_compress(&info);
  std::free(out);
  return bytes;
}

// Collects progress messages.
struct Messages : ProgressListener {
  std::vector<std::string> lines;
  void on_event(const ProgressEvent& event) override {
    if (event.kind == ProgressEvent::Kind::Message) lines.push_back(event.text);
  }
};

}  // namespace

TEST(ImageDecode, PngPixelsAreOpenCvsForEveryColourTypeDepthTransparencyAndInterlacing) {
  struct Case {
    std::string name;
    int color_type, bit_depth;
    std::string extra;  // chunks before IDAT
    int channels;       // what OpenCV gives
  };
  const std::string plte = chunk("PLTE", std::string("\x10\x20\x30\xff\x00\x80\x01\x02\x03\x40\x50\x60", 12));
  const std::vector<Case> cases = {
      {"gray 1 bit", 0, 1, "", 1},
      {"gray 4 bit", 0, 4, "", 1},
      {"gray 8 bit", 0, 8, "", 1},
      {"gray 16 bit", 0, 16, "", 1},
      {"gray 8 bit, tRNS", 0, 8, chunk("tRNS", std::string("\x00\x05", 2)), 1},
      {"gray+alpha 8 bit", 4, 8, "", 4},
      {"gray+alpha 16 bit", 4, 16, "", 4},
      {"rgb 8 bit", 2, 8, "", 3},
      {"rgb 16 bit", 2, 16, "", 3},
      {"rgb 8 bit, tRNS", 2, 8, chunk("tRNS", std::string("\x00\x05\x00\x06\x00\x07", 6)), 4},
      {"palette 8 bit", 3, 8, plte, 3},
      {"palette 2 bit, tRNS", 3, 2, plte + chunk("tRNS", std::string("\x00\x80", 2)), 4},
      {"rgba 8 bit", 6, 8, "", 4},
      {"rgba 16 bit", 6, 16, "", 4},
  };
  const int width = 5, height = 3;
  for (const Case& c : cases) {
    const int per_pixel = c.color_type == 0 || c.color_type == 3 ? 1
                          : c.color_type == 4                    ? 2
                          : c.color_type == 2                    ? 3
                                                                 : 4;
    const int max_value = c.color_type == 3 ? 3 : (1 << c.bit_depth) - 1;  // palette: 4 entries
    std::vector<int> samples(size_t(width) * height * per_pixel);
    for (size_t i = 0; i < samples.size(); ++i) samples[i] = int((i * 2654435761u) % uint32_t(max_value + 1));
    if (c.bit_depth >= 8 && c.color_type != 3)  // the first pixel has the tRNS colour of the gray and RGB cases
      for (int k = 0; k < std::min(per_pixel, 3); ++k) samples[size_t(k)] = 5 + k;
    for (bool interlaced : {false, true}) {
      SCOPED_TRACE(c.name + (interlaced ? ", interlaced" : ""));
      const std::string png = make_png(width, height, c.color_type, c.bit_depth, samples, interlaced, c.extra);
      const Image expected = opencv_decode(png);
      ASSERT_EQ(expected.channels, c.channels);
      expect_same_pixels(decode(png), expected);
    }
  }
}

// A text chunk whose CRC is wrong is a libpng warning (the chunk is dropped and the image decodes); a
// broken IDAT is a libpng error. Neither may print libpng's own lines ("libpng warning: ...", as OpenCV's
// decoder let them): load_image reports the warning as a progress message naming the file, and the error
// as the Error's reason.
TEST(ImageDecode, LibpngMessagesComeInTheProjectsWords) {
  const fs::path dir = u3d::testing::fresh_temp_dir("png");
  auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    return dir / name;
  };
  const std::vector<int> samples = {0, 255, 128, 7};
  std::string text = chunk("tEXt", std::string("Comment\0hello", 13));
  text[text.size() - 1] ^= 0x5a;  // the CRC
  const fs::path left = write("left.png", make_png(2, 2, 0, 8, samples, false, text));

  Messages messages;
  ::testing::internal::CaptureStderr();
  Image image;
  {
    ProgressScope scope(&messages);
    image = load_image(left);
  }
  std::string printed = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "");
  ASSERT_EQ(image.channels, 1);
  EXPECT_EQ(image.data[1], 1.f);
  ASSERT_EQ(messages.lines.size(), 1u);
  EXPECT_EQ(messages.lines[0], "warning: image " + left.string() + ": tEXt: CRC error");

  std::string broken = make_png(2, 2, 0, 8, samples);
  broken[broken.find("IDAT") + 6] ^= 0x40;  // inside the zlib stream, so IDAT's CRC fails
  const fs::path right = write("right.png", broken);
  ::testing::internal::CaptureStderr();
  try {
    load_image(right);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot decode image " + right.string() + ": IDAT: CRC error");
  }
  printed = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "");

  const std::string whole = make_png(2, 2, 0, 8, samples);
  const fs::path cut = write("cut.png", whole.substr(0, whole.size() / 2));
  ::testing::internal::CaptureStderr();
  try {
    load_image(cut);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cut.png: the data ends early"), std::string::npos) << e.what();
  }
  printed = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "");
  fs::remove_all(dir);
}

TEST(ImageDecode, JpegPixelsAreOpenCvsForGrayColourAndCmyk) {
  cv::Mat colour(37, 53, CV_8UC3), gray(37, 53, CV_8UC1);
  cv::randu(colour, 0, 256);
  cv::randu(gray, 0, 256);
  std::vector<std::string> jpegs;
  for (const cv::Mat& m : {colour, gray})
    for (int progressive : {0, 1}) {
      std::vector<unsigned char> bytes;
      cv::imencode(".jpg", m, bytes, {cv::IMWRITE_JPEG_QUALITY, 90, cv::IMWRITE_JPEG_PROGRESSIVE, progressive});
      jpegs.emplace_back(bytes.begin(), bytes.end());
    }
  jpegs.push_back(libjpeg_encode(29, 17, 3, true));
  jpegs.push_back(libjpeg_encode(29, 17, 4, false));
  for (size_t j = 0; j < jpegs.size(); ++j) {
    SCOPED_TRACE("jpeg " + std::to_string(j));
    const std::string& jpeg = jpegs[j];
    ASSERT_TRUE(is_jpeg_signature(reinterpret_cast<const unsigned char*>(jpeg.data()), jpeg.size()));
    const Image expected = opencv_decode(jpeg);
    const Image got = decode_jpeg(reinterpret_cast<const unsigned char*>(jpeg.data()), jpeg.size(), "test.jpg");
    EXPECT_EQ(got.channels, j == 2 || j == 3 ? 1 : 3);
    expect_same_pixels(got, expected);
  }
}

// A JPEG that ends early is decoded (libjpeg fills the rest in) with a warning; one whose header is
// corrupt is an error. Neither may print libjpeg's own lines ("Premature end of JPEG file").
TEST(ImageDecode, LibjpegMessagesComeInTheProjectsWords) {
  const fs::path dir = u3d::testing::fresh_temp_dir("jpeg");
  cv::Mat colour(64, 64, CV_8UC3);
  cv::randu(colour, 0, 256);
  std::vector<unsigned char> bytes;
  cv::imencode(".jpg", colour, bytes);
  const std::string jpeg(bytes.begin(), bytes.end());

  const fs::path cut = dir / "cut.jpg";
  std::ofstream(cut, std::ios::binary) << jpeg.substr(0, jpeg.size() * 2 / 3);
  Messages messages;
  ::testing::internal::CaptureStderr();
  Image image;
  {
    ProgressScope scope(&messages);
    image = load_image(cut);
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(image.width, 64);
  ASSERT_EQ(messages.lines.size(), 1u);
  EXPECT_EQ(messages.lines[0], "warning: image " + cut.string() + ": Premature end of JPEG file");

  std::string corrupt = jpeg;
  const size_t sof = corrupt.find("\xff\xc0");
  ASSERT_NE(sof, std::string::npos);
  corrupt[sof + 4] = char(0xff);  // the frame header's length runs past the file's markers
  corrupt[sof + 9] = char(7);     // seven components
  const fs::path bad = dir / "bad.jpg";
  std::ofstream(bad, std::ios::binary) << corrupt;
  ::testing::internal::CaptureStderr();
  try {
    load_image(bad);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cannot decode image " + bad.string() + ": ", 0), 0u) << e.what();
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  fs::remove_all(dir);
}

// peek_image_size reads the size from the header alone: the size the decoders give for PNG and JPEG
// (baseline and progressive), a size no decoder could allocate from a header-only file, and an Error for
// headers cut short or other formats.
TEST(ImageDecode, PeekImageSizeReadsTheHeaderAlone) {
  cv::Mat colour(37, 53, CV_8UC3);
  cv::randu(colour, 0, 256);
  for (const std::string ext : {".png", ".jpg"})
    for (int progressive : {0, 1}) {
      std::vector<unsigned char> bytes;
      cv::imencode(ext, colour, bytes, {cv::IMWRITE_JPEG_PROGRESSIVE, progressive});
      const ImageSize size = peek_image_size(bytes.data(), bytes.size(), "test" + ext);
      EXPECT_EQ(size.width, 53) << ext;
      EXPECT_EQ(size.height, 37) << ext;
      const std::string cut(bytes.begin(), bytes.begin() + 20);
      EXPECT_THROW(peek_image_size(reinterpret_cast<const unsigned char*>(cut.data()), cut.size(), "cut" + ext), Error)
          << ext;
    }
  const std::string huge = "\x89PNG\r\n\x1a\n" + chunk("IHDR", be32(100000) + be32(100000) + std::string("\x08\x06\0\0\0", 5));
  const ImageSize size = peek_image_size(reinterpret_cast<const unsigned char*>(huge.data()), huge.size(), "huge.png");
  EXPECT_EQ(size.width, 100000);
  EXPECT_EQ(size.height, 100000);
  const std::string gif = "GIF89a\x01\x00\x01\x00";
  EXPECT_THROW(peek_image_size(reinterpret_cast<const unsigned char*>(gif.data()), gif.size(), "x.gif"), Error);
}
