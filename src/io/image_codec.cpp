#include "io/image_codec.h"

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace u3d {

TextureFormat parse_texture_format(const std::string& text) {
  if (text == "png") return TextureFormat::Png;
  if (text == "jpg" || text == "jpeg") return TextureFormat::Jpeg;
  throw Error("unknown texture format '" + text + "' (use png or jpg)");
}

const char* texture_extension(TextureFormat format) { return format == TextureFormat::Png ? ".png" : ".jpg"; }

const char* texture_mime_type(TextureFormat format) { return format == TextureFormat::Png ? "image/png" : "image/jpeg"; }

std::vector<unsigned char> encode_png(const Image& image, const std::string& what) {
  return encode_image(image, TextureFormat::Png, what);
}

std::vector<unsigned char> encode_image(const Image& image, TextureFormat format, const std::string& what) {
  require(!image.empty() && image.width > 0 && image.height > 0, "cannot encode empty " + what);
  require(image.channels == 1 || image.channels == 3 || image.channels == 4,
          "cannot encode " + what + " with " + std::to_string(image.channels) + " channels");
  for (float v : image.data) require(!std::isnan(v), "refusing to encode " + what + " with NaN values");
  cv::Mat f = cv::Mat(image.height, image.width, CV_32FC(image.channels), const_cast<float*>(image.data.data())).clone();
  const bool jpeg = format == TextureFormat::Jpeg;
  if (image.channels == 3) cv::cvtColor(f, f, cv::COLOR_RGB2BGR);
  else if (image.channels == 4) cv::cvtColor(f, f, jpeg ? cv::COLOR_RGBA2BGR : cv::COLOR_RGBA2BGRA);
  cv::Mat bytes8;
  f.convertTo(bytes8, CV_8U, 255.0);  // saturating and rounding
  std::vector<unsigned char> out;
  const std::vector<int> params = jpeg ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, 95} : std::vector<int>{};
  require(cv::imencode(texture_extension(format), bytes8, out, params),
          "cannot encode " + what + (jpeg ? " as JPEG" : " as PNG"));
  return out;
}

}  // namespace u3d
