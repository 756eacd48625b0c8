#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/error.h"
#include "core/image.h"

namespace fs = std::filesystem;
using namespace u3d;

namespace {
fs::path temp_dir() {
  fs::path d = fs::temp_directory_path() / ("u3d_test_image_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
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
