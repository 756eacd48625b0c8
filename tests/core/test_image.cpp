#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/error.h"
#include "core/image.h"
#include "core/temp_dir.h"

namespace fs = std::filesystem;
using namespace u3d;

namespace {
fs::path temp_dir() {
  static const fs::path d = u3d::testing::fresh_temp_dir("image");
  return d;
}

// The smallest PNG file structure with the given size in its header: IHDR (8-bit RGBA), a short IDAT
// and IEND, with their CRCs.
void write_png_chunks(const fs::path& path, uint32_t width, uint32_t height) {
  auto crc32 = [](const std::string& bytes) {
    uint32_t c = 0xffffffffu;
    for (unsigned char b : bytes) {
      c ^= b;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return c ^ 0xffffffffu;
  };
  auto be32 = [](uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  };
  auto chunk = [&](const std::string& type, const std::string& data) {
    return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
  };
  const std::string ihdr = be32(width) + be32(height) + std::string{8, 6, 0, 0, 0};
  const std::string idat("\x78\x9c\x63\x60\x00\x00\x00\x02\x00\x01", 10);  // zlib of one zero byte
  std::ofstream(path, std::ios::binary) << std::string("\x89PNG\r\n\x1a\n", 8) << chunk("IHDR", ihdr)
                                        << chunk("IDAT", idat) << chunk("IEND", "");
}
}  // namespace

TEST(Image, PngRoundTrip8And16BitKeepsAlpha) {
  Image im(5, 3, 4);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) {
      im.at(x, y, 0) = x / 4.f;
      im.at(x, y, 1) = y / 2.f;
      im.at(x, y, 2) = 0.25f;
      im.at(x, y, 3) = (x + y) % 2 ? 1.f : 0.f;
    }
  for (int bits : {8, 16}) {
    fs::path p = temp_dir() / ("rt" + std::to_string(bits) + ".png");
    save_image(im, p, bits);
    Image back = load_image(p);
    ASSERT_EQ(back.width, 5);
    ASSERT_EQ(back.height, 3);
    ASSERT_EQ(back.channels, 4);
    float tol = bits == 8 ? 0.5f / 255.f + 1e-6f : 0.5f / 65535.f + 1e-7f;
    for (size_t i = 0; i < im.data.size(); ++i) EXPECT_NEAR(back.data[i], im.data[i], tol) << "bits " << bits;
  }
}

// quantized_8bit is what an 8-bit PNG gives back, bit for bit: on every level, half-way between levels
// (where the rounding rule shows), just off them, and outside [0, 1].
TEST(Image, Quantized8BitIsWhatThePngGivesBack) {
  for (int channels : {1, 3, 4}) {
    Image im(256, 5, channels);
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < channels; ++c) {
        im.at(x, 0, c) = float(x) / 255.f;
        im.at(x, 1, c) = (float(x) + 0.5f) / 255.f;
        im.at(x, 2, c) = (float(x) + 0.5f) / 255.f - 1e-7f * float(c + 1);
        im.at(x, 3, c) = std::nextafter(float(x) / 255.f, 2.f);
        im.at(x, 4, c) = x % 2 ? 1.f + float(x) : -float(x);
      }
    const fs::path p = temp_dir() / ("quantized" + std::to_string(channels) + ".png");
    save_image(im, p);
    const Image back = load_image(p), q = quantized_8bit(im);
    ASSERT_EQ(q.channels, channels);
    ASSERT_EQ(q.data.size(), back.data.size());
    for (size_t i = 0; i < q.data.size(); ++i) ASSERT_EQ(q.data[i], back.data[i]) << i;
    EXPECT_EQ(quantized_8bit(q).data, q.data);
  }
}

// An opaque red half beside a transparent half whose colour is blue: shrunk, the pixels that straddle
// the edge are part red and part transparent; resize_premultiplied keeps them red (resize_image turns
// them purple), gives the alpha resize_image gives, and colour 0 where nothing is opaque.
TEST(Image, ResizePremultipliedKeepsTheBackgroundsColourOutOfTheEdge) {
  Image im(8, 4, 4, 0.f);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x) {
      const bool red = x < 3;
      im.at(x, y, 0) = red ? 1.f : 0.f;
      im.at(x, y, 2) = red ? 0.f : 1.f;
      im.at(x, y, 3) = red ? 1.f : 0.f;
    }
  const Image plain = resize_image(im, 4, 2), small = resize_premultiplied(im, 4, 2);
  ASSERT_EQ(small.channels, 4);
  ASSERT_EQ(small.width, 4);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) {
      EXPECT_FLOAT_EQ(small.at(x, y, 3), plain.at(x, y, 3));
      const bool some_red = small.at(x, y, 3) > 0.f;
      EXPECT_FLOAT_EQ(small.at(x, y, 0), some_red ? 1.f : 0.f) << x;
      EXPECT_FLOAT_EQ(small.at(x, y, 2), 0.f) << x;
    }
  EXPECT_FLOAT_EQ(small.at(1, 0, 3), 0.5f);   // the straddling pixel: half opaque
  EXPECT_FLOAT_EQ(plain.at(1, 0, 2), 0.5f);   // where resize_image mixes in the blue
  EXPECT_THROW(resize_premultiplied(Image(4, 4, 3), 2, 2), Error);
}

TEST(Image, RgbChannelOrderIsRgb) {
  Image im(1, 1, 3);
  im.at(0, 0, 0) = 1.f;  // pure red
  fs::path p = temp_dir() / "red.png";
  save_image(im, p);
  Image back = load_image_rgba(p);
  EXPECT_FLOAT_EQ(back.at(0, 0, 0), 1.f);
  EXPECT_FLOAT_EQ(back.at(0, 0, 2), 0.f);
  EXPECT_FLOAT_EQ(back.at(0, 0, 3), 1.f);
}

TEST(Image, BadInputsGiveErrors) {
  fs::path d = temp_dir();
  EXPECT_THROW(load_image(d / "missing.png"), Error);
  {
    std::ofstream(d / "corrupt.png") << "\x89PNG not really";
  }
  EXPECT_THROW(load_image(d / "corrupt.png"), Error);
  Image nan_im(2, 2, 3, std::nanf(""));
  EXPECT_THROW(save_image(nan_im, d / "nan.png"), Error);
  EXPECT_FALSE(fs::exists(d / "nan.png"));
  EXPECT_THROW(save_image(Image(2, 2, 3), d / "no_such_dir" / "x.png"), Error);
}

// A device or pipe given as an image: /dev/stdin would block and /dev/zero never ends, so anything that
// is not a regular file is refused before it is read.
TEST(Image, DevicesAndFoldersAreRefusedBeforeReading) {
  for (const fs::path& path : {fs::path("/dev/null"), temp_dir()}) {
    try {
      load_image(path);
      ADD_FAILURE() << path << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("got a folder or device"), std::string::npos) << e.what();
    }
  }
}

// 128 bytes, "DICM", one more: OpenCV handed that to GDCM, whose assertion aborted the process (found by
// fuzz_image). It must be an Error like any other file that is not a PNG or JPEG image.
TEST(Image, DicomSignatureIsAnErrorNotAnAbort) {
  const fs::path path = temp_dir() / "scan.png";
  {
    std::ofstream out(path, std::ios::binary);
    out << std::string(128, '\xa7') << "DICM" << '\xa4';
  }
  try {
    load_image(path);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scan.png: not a PNG or JPEG image"), std::string::npos) << e.what();
  }
}

// A PNG whose header claims 65535 x 65535 pixels is refused in plain words (OpenCV's decoder, used
// before, refused it with its raw assertion text).
TEST(Image, OversizedPngIsAnErrorInPlainWords) {
  const fs::path path = temp_dir() / "huge.png";
  write_png_chunks(path, 65535, 65535);
  try {
    load_image(path);
    FAIL() << "accepted";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("huge.png: larger than the 2^30 pixels"), std::string::npos) << message;
    EXPECT_EQ(message.find("OpenCV"), std::string::npos) << message;
  }
}
