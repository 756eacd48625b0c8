#include "core/image.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_decode.h"

namespace u3d {

namespace fs = std::filesystem;

Image::Image(int w, int h, int c, float fill) : width(w), height(h), channels(c), data(size_t(w) * h * c, fill) {}

namespace {

cv::Mat to_mat(const Image& im) {
  return cv::Mat(im.height, im.width, CV_32FC(im.channels), const_cast<float*>(im.data.data()));
}

Image from_mat_float(const cv::Mat& m) {
  Image im(m.cols, m.rows, m.channels());
  cv::Mat dst(m.rows, m.cols, CV_32FC(m.channels()), im.data.data());
  m.copyTo(dst);
  return im;
}

}  // namespace

Image load_image(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error("image not found: " + path.string());
  // A folder, and a device or pipe, which would block (/dev/stdin) or never end (/dev/zero).
  if (!fs::is_regular_file(path, ec)) throw Error("expected an image file, got a folder or device: " + path.string());
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read image " + path.string());
  // The signature first, so that a large file of another kind is refused without being read.
  unsigned char head[8] = {};
  in.read(reinterpret_cast<char*>(head), sizeof(head));
  const size_t head_size = size_t(in.gcount());
  if (!is_png_signature(head, head_size) && !is_jpeg_signature(head, head_size))
    return decode_image(head, head_size, "image " + path.string());  // (refuses it, naming the file)
  in.clear();
  in.seekg(0);
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decode_image(bytes.data(), bytes.size(), "image " + path.string());
}

Image load_image_rgba(const fs::path& path) {
  Image src = load_image(path);
  if (src.channels == 4) return src;
  Image out(src.width, src.height, 4, 1.f);
  for (size_t i = 0; i < src.pixel_count(); ++i) {
    for (int c = 0; c < 3; ++c) out.data[i * 4 + c] = src.data[i * src.channels + (src.channels == 1 ? 0 : c)];
  }
  return out;
}

void save_image(const Image& image, const fs::path& path, int bit_depth) {
  require(!image.empty() && image.width > 0 && image.height > 0, "cannot write empty image " + path.string());
  require(image.channels == 1 || image.channels == 3 || image.channels == 4,
          "cannot write image with " + std::to_string(image.channels) + " channels: " + path.string());
  require(bit_depth == 8 || bit_depth == 16, "bit depth must be 8 or 16, got " + std::to_string(bit_depth));
  for (float v : image.data) require(!std::isnan(v), "refusing to write image with NaN values: " + path.string());
  std::string ext = path.extension().string();
  for (auto& ch : ext) ch = char(std::tolower(ch));
  bool jpeg = ext == ".jpg" || ext == ".jpeg";
  require(ext == ".png" || jpeg, "unsupported image extension '" + ext + "' (use .png or .jpg): " + path.string());
  if (jpeg) bit_depth = 8;

  cv::Mat f = to_mat(image).clone();
  if (image.channels == 3) cv::cvtColor(f, f, cv::COLOR_RGB2BGR);
  else if (image.channels == 4) cv::cvtColor(f, f, jpeg ? cv::COLOR_RGBA2BGR : cv::COLOR_RGBA2BGRA);
  cv::Mat out;
  f.convertTo(out, bit_depth == 16 ? CV_16U : CV_8U, bit_depth == 16 ? 65535.0 : 255.0);  // saturating, rounds
  write_atomically(path, [&](const fs::path& tmp) {
    bool ok = false;
    try {
      ok = cv::imwrite(tmp.string(), out);
    } catch (const cv::Exception& e) {
      throw Error("cannot write image " + path.string() + ": " + e.what());
    }
    if (!ok) throw Error("cannot write image " + path.string());
  });
}

Image quantized_8bit(const Image& image) {
  cv::Mat levels;
  to_mat(image).convertTo(levels, CV_8U, 255.0);  // as save_image
  Image out(image.width, image.height, image.channels);
  const float scale = float(1.0 / 255.0);  // as the PNG decoder (core/image_decode.cpp)
  for (size_t i = 0; i < out.data.size(); ++i) out.data[i] = float(levels.data[i]) * scale;
  return out;
}

Image resize_image(const Image& image, int width, int height) {
  require(width > 0 && height > 0, "resize to an empty size");
  if (width == image.width && height == image.height) return image;
  cv::Mat dst;
  int interp = (width < image.width) ? cv::INTER_AREA : cv::INTER_LINEAR;
  cv::resize(to_mat(image), dst, cv::Size(width, height), 0, 0, interp);
  return from_mat_float(dst);
}

Image resize_premultiplied(const Image& rgba, int width, int height) {
  require(rgba.channels == 4, "resize_premultiplied: the image must be RGBA");
  Image premultiplied(rgba.width, rgba.height, 4);
  for (size_t p = 0; p < rgba.pixel_count(); ++p) {
    const float* in = rgba.data.data() + p * 4;
    float* out = premultiplied.data.data() + p * 4;
    for (int c = 0; c < 3; ++c) out[c] = in[c] * in[3];
    out[3] = in[3];
  }
  Image small = resize_image(premultiplied, width, height);
  for (size_t p = 0; p < small.pixel_count(); ++p) {
    const float a = small.data[p * 4 + 3];
    for (int c = 0; c < 3; ++c) small.data[p * 4 + c] = a > 1e-6f ? std::min(1.f, small.data[p * 4 + c] / a) : 0.f;
  }
  return small;
}

}  // namespace u3d
