#include "core/view_set.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_decode.h"
#include "core/progress.h"

namespace u3d {
namespace {

constexpr float kMinNormalLength = 0.6f, kMaxNormalLength = 1.4f;
// Visible surfaces face their camera: the mean of n . toward_camera over a view's mask is about 2/3
// for a sphere. A mean below this means the normals are in the other space (or flipped).
constexpr float kMinMeanFacing = 0.1f;
constexpr int kMinResolution = 16;

bool has_png_signature(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[8] = {};
  in.read(reinterpret_cast<char*>(head), 8);
  return is_png_signature(head, size_t(in.gcount()));
}

void require_finite(const Image& image, const std::string& name) {
  const bool finite = std::all_of(image.data.begin(), image.data.end(), [](float v) { return std::isfinite(v); });
  require(finite, name + ": contains NaN or infinite values");  // the message is built once, not per value
}

Eigen::Vector3f decode_normal(const float* px) { return {2.f * px[0] - 1.f, 2.f * px[1] - 1.f, 2.f * px[2] - 1.f}; }

bool looks_like_unit_normal(const Eigen::Vector3f& n) {
  float len = n.norm();
  return len >= kMinNormalLength && len <= kMaxNormalLength;
}

// Mask of an image resampled to another resolution (area/bilinear, then thresholded).
std::vector<float> resampled_mask(const Image& image, int resolution) {
  Image alpha(image.width, image.height, 1);
  for (size_t i = 0; i < image.pixel_count(); ++i) alpha.data[i] = image.data[i * image.channels + image.channels - 1];
  Image r = resize_image(alpha, resolution, resolution);
  std::vector<float> out(r.data.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = is_foreground(r.data[i]) ? 1.f : 0.f;
  return out;
}

bool has_alpha(const Image& image) { return image.channels == 2 || image.channels == 4; }

// Any of gray, gray+alpha, RGB, RGBA -> RGBA (missing alpha = 1).
Image to_rgba(const Image& image) {
  if (image.channels == 4) return image;
  Image out(image.width, image.height, 4, 1.f);
  const bool gray = image.channels < 3;
  for (size_t i = 0; i < image.pixel_count(); ++i) {
    const float* px = &image.data[i * image.channels];
    for (int c = 0; c < 3; ++c) out.data[i * 4 + c] = px[gray ? 0 : c];
    if (has_alpha(image)) out.data[i * 4 + 3] = px[image.channels - 1];
  }
  return out;
}

void check_square_and_size(const Image& image, const std::string& name) {
  require(image.width == image.height, name + ": views must be square, got " + std::to_string(image.width) + "x" +
                                           std::to_string(image.height));
  require(image.width >= kMinResolution, name + ": resolution " + std::to_string(image.width) +
                                             " is too small (at least " + std::to_string(kMinResolution) + ")");
}

void check_mask_coverage(const Image& rgba, const std::string& name) {
  size_t fg = 0;
  for (size_t i = 0; i < rgba.pixel_count(); ++i) fg += is_foreground(rgba.data[i * 4 + 3]);
  require(fg > 0, name + ": the mask is empty (no pixel with alpha >= 0.5)");
  require(fg < rgba.pixel_count(),
          name + ": the mask covers the whole image (no background); the object must fit inside the view "
                 "with a transparent background");
}

}  // namespace

NormalSpace parse_normal_space(const std::string& text) {
  if (text == "world") return NormalSpace::World;
  if (text == "camera") return NormalSpace::Camera;
  throw Error("normal space must be 'world' or 'camera', got '" + text + "'");
}

std::string view_file_name(View v, bool normal) {
  return std::string(view_name(v)) + (normal ? "_normal.png" : "_rgb.png");
}

ViewSet make_view_set(std::array<Image, 4> rgb, std::array<Image, 4> normal_maps, NormalSpace space,
                      const std::array<std::string, 4>& rgb_names, const std::array<std::string, 4>& normal_names,
                      NormalCheck check) {
  const auto require_content = [check](bool cond, const std::string& message) {
    if (check == NormalCheck::kGiven)
      require(cond, message);
    else if (!cond)
      progress("warning: " + message);
  };
  // Sizes first: every later check assumes consistent, square images.
  for (size_t i = 0; i < 4; ++i) {
    check_square_and_size(rgb[i], rgb_names[i]);
    check_square_and_size(normal_maps[i], normal_names[i]);
    require_finite(rgb[i], rgb_names[i]);
    require_finite(normal_maps[i], normal_names[i]);
    require(rgb[i].width == rgb[0].width, "size mismatch: " + rgb_names[i] + " is " + std::to_string(rgb[i].width) +
                                              " px but " + rgb_names[0] + " is " + std::to_string(rgb[0].width) +
                                              " px (all RGB views must share one resolution)");
    require(normal_maps[i].width == normal_maps[0].width,
            "size mismatch: " + normal_names[i] + " is " + std::to_string(normal_maps[i].width) + " px but " +
                normal_names[0] + " is " + std::to_string(normal_maps[0].width) +
                " px (all normal maps must share one resolution)");
  }

  ViewSet set;
  for (View v : kAllViews) {
    const size_t i = size_t(v);
    require(normal_maps[i].channels >= 3, normal_names[i] + ": a normal map needs RGB channels, got a gray image");
    const Image& nm = normal_maps[i];
    const int nres = nm.width;
    const bool normal_has_alpha = nm.channels == 4, rgb_has_alpha = has_alpha(rgb[i]);

    bool any_light = false;
    for (size_t p = 0; p < nm.pixel_count() && !any_light; ++p)
      for (int c = 0; c < std::min(3, nm.channels); ++c) any_light |= nm.data[p * nm.channels + c] > 1.f / 255.f;
    require(any_light, normal_names[i] + ": the normal map is all black");

    // The normal-map mask, by the rules of view_set.h.
    std::vector<float> mask(nm.pixel_count());
    if (normal_has_alpha) {
      for (size_t p = 0; p < mask.size(); ++p) mask[p] = is_foreground(nm.data[p * 4 + 3]) ? 1.f : 0.f;
    } else if (rgb_has_alpha) {
      mask = resampled_mask(rgb[i], nres);
    } else {
      for (size_t p = 0; p < mask.size(); ++p)
        mask[p] = looks_like_unit_normal(decode_normal(&nm.data[p * nm.channels])) ? 1.f : 0.f;
    }

    Image normals(nres, nres, 4, 0.f);
    const Camera cam = view_camera(v, nres);
    const Eigen::Matrix3f camera_to_world = cam.rotation().transpose();
    const Eigen::Vector3f toward = cam.toward_camera();
    size_t fg = 0, bad = 0;
    double facing = 0.0;
    for (size_t p = 0; p < mask.size(); ++p) {
      normals.data[p * 4 + 3] = mask[p];
      if (mask[p] == 0.f) continue;
      ++fg;
      Eigen::Vector3f n = decode_normal(&nm.data[p * nm.channels]);
      if (!looks_like_unit_normal(n)) ++bad;
      n = n.norm() > 1e-6f ? Eigen::Vector3f(n.normalized()) : Eigen::Vector3f(toward);
      if (space == NormalSpace::Camera) n = camera_to_world * n;
      facing += n.dot(toward);
      for (int c = 0; c < 3; ++c) normals.data[p * 4 + c] = n[c];
    }
    require(fg > 0, normal_names[i] + ": the mask is empty (no foreground pixel)");
    require(fg < mask.size(), normal_names[i] +
                                  ": the mask covers the whole image (no background); the object must fit inside "
                                  "the view with a transparent background");
    require_content(bad * 2 <= fg, normal_names[i] + ": " + std::to_string(100 * bad / fg) +
                                       "% of the foreground pixels are not unit normals encoded as (n+1)/2");
    require_content(facing / double(fg) >= kMinMeanFacing,
                    normal_names[i] + ": the normals face away from the " + view_name(v) + " camera (mean cosine " +
                        std::to_string(facing / double(fg)) +
                        (check == NormalCheck::kGiven ? "); are they in the other space (see --normal-space)?" : ")"));
    set.views[i].normals = std::move(normals);

    Image color = to_rgba(rgb[i]);
    if (!rgb_has_alpha) {
      Image m(nres, nres, 1);
      m.data = mask;
      Image r = resize_image(m, color.width, color.height);
      for (size_t p = 0; p < color.pixel_count(); ++p) color.data[p * 4 + 3] = is_foreground(r.data[p]) ? 1.f : 0.f;
    }
    check_mask_coverage(color, rgb_names[i]);
    set.views[i].rgb = std::move(color);
  }
  return set;
}

ViewSet load_view_set(const std::filesystem::path& dir, NormalSpace space, NormalCheck check) {
  require(path_exists(dir) && std::filesystem::is_directory(dir),
          "views folder " + dir.string() + " does not exist or is not a folder");
  std::string missing;
  for (View v : kAllViews)
    for (bool normal : {false, true})
      if (const auto path = dir / view_file_name(v, normal); !path_exists(path) || !std::filesystem::is_regular_file(path))
        missing += (missing.empty() ? "" : ", ") + view_file_name(v, normal);
  require(missing.empty(), "views folder " + dir.string() + " lacks " + missing);

  std::array<Image, 4> rgb, normal_maps;
  std::array<std::string, 4> rgb_names, normal_names;
  for (View v : kAllViews) {
    const size_t i = size_t(v);
    for (bool normal : {false, true}) {
      const std::filesystem::path path = dir / view_file_name(v, normal);
      require(has_png_signature(path), path.string() + ": not a PNG file");
      (normal ? normal_names : rgb_names)[i] = path.string();
      (normal ? normal_maps : rgb)[i] = load_image(path);
    }
  }
  return make_view_set(std::move(rgb), std::move(normal_maps), space, rgb_names, normal_names, check);
}

}  // namespace u3d
