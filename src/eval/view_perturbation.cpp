#include "eval/view_perturbation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "core/atomic_file.h"
#include "core/error.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

Vec3f decode_normal(const float* px) { return Vec3f(2 * px[0] - 1, 2 * px[1] - 1, 2 * px[2] - 1); }

void encode_normal(float* px, const Vec3f& n) {
  for (int c = 0; c < 3; ++c) px[c] = std::clamp(0.5f * (n[c] + 1), 0.f, 1.f);
}

// Resamples `src` at the continuous source pixel index `source(x, y)` of every output pixel (bilinear
// on alpha-premultiplied colour, transparent outside the source).
template <class SourceOf>
Image resample(const Image& src, bool unit_vectors, SourceOf source) {
  require(src.channels == 4, "view images must be RGBA");
  Image out(src.width, src.height, 4, 0.f);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      const Eigen::Vector2f f = source(x, y);
      const float fx = f.x(), fy = f.y();
      int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
      float tx = fx - x0, ty = fy - y0;
      float acc[4] = {0, 0, 0, 0};
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          int sx = x0 + dx, sy = y0 + dy;
          if (sx < 0 || sy < 0 || sx >= src.width || sy >= src.height) continue;  // transparent outside
          float w = (dx ? tx : 1 - tx) * (dy ? ty : 1 - ty);
          const float* p = src.pixel(sx, sy);
          float wa = w * p[3];
          if (unit_vectors) {
            Vec3f n = decode_normal(p);
            for (int k = 0; k < 3; ++k) acc[k] += wa * n[k];
          } else {
            for (int k = 0; k < 3; ++k) acc[k] += wa * p[k];
          }
          acc[3] += wa;
        }
      float* o = out.pixel(x, y);
      if (acc[3] <= 0) continue;
      o[3] = std::min(acc[3], 1.f);
      if (unit_vectors) {
        Vec3f n(acc[0], acc[1], acc[2]);
        encode_normal(o, n.norm() > 0 ? Vec3f(n.normalized()) : n);
      } else {
        for (int k = 0; k < 3; ++k) o[k] = std::clamp(acc[k] / acc[3], 0.f, 1.f);
      }
    }
  return out;
}

// One stream per (seed, perturbation kind, view): a view's field does not depend on the other views
// or on which other perturbations are on.
uint64_t field_seed(uint64_t seed, int kind, View v) { return seed * 16 + uint64_t(kind) * 4 + uint64_t(v) + 0x9e3779b9ull; }

}  // namespace

Image warp_image(const Image& src, const ViewWarp& warp, bool unit_vectors) {
  require(warp.scale > 0, "view scale must be positive, got " + std::to_string(warp.scale));
  const float theta = warp.rotate_deg * std::numbers::pi_v<float> / 180.f;
  const float c = std::cos(theta), s = std::sin(theta);
  const float cx = 0.5f * src.width, cy = 0.5f * src.height;
  return resample(src, unit_vectors, [&](int x, int y) {
    // Output offset in "up" coordinates, mapped back by the inverse rotation and scale.
    float u = (x + 0.5f - cx), v = (cy - (y + 0.5f));
    float su = (c * u + s * v) / warp.scale, sv = (-s * u + c * v) / warp.scale;
    return Eigen::Vector2f(cx + su - 0.5f, cy - sv - 0.5f);  // continuous source pixel index
  });
}

SmoothField::SmoothField(const SmoothFieldSpec& spec, uint64_t seed) {
  require(std::isfinite(spec.amplitude) && std::isfinite(spec.scale_px),
          "smooth field: amplitude and scale must be finite numbers");
  require(!spec.active() || spec.scale_px > 0, "smooth field: the scale must be positive");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> angle(0.f, 2 * std::numbers::pi_v<float>);
  const float k = spec.active() ? 2 * std::numbers::pi_v<float> / spec.scale_px : 0.f;
  for (int m = 0; m < 2 * kModes; ++m) {
    const float direction = angle(rng);
    wave_[size_t(m)] = k * Eigen::Vector2f(std::cos(direction), std::sin(direction));
    phase_[size_t(m)] = angle(rng);
  }
  // kModes sinusoids of distinct wave vectors have mean square kModes / 2 over the plane.
  mode_amplitude_ = spec.amplitude * std::sqrt(2.f / kModes);
}

Eigen::Vector2f SmoothField::at(float x, float y) const {
  Eigen::Vector2f out(0, 0);
  const Eigen::Vector2f p(x, y);
  for (int m = 0; m < 2 * kModes; ++m) out[m / kModes] += std::sin(wave_[size_t(m)].dot(p) + phase_[size_t(m)]);
  return mode_amplitude_ * out;
}

Image displace_image(const Image& src, const SmoothField& displacement, bool unit_vectors) {
  return resample(src, unit_vectors, [&](int x, int y) {
    const Eigen::Vector2f centre(x + 0.5f, y + 0.5f);
    return Eigen::Vector2f(centre - displacement.at(centre.x(), centre.y()) - Eigen::Vector2f(0.5f, 0.5f));
  });
}

void bend_normals(Image& normal_map, const SmoothField& tilt_deg, const Eigen::Vector3f& right,
                  const Eigen::Vector3f& up) {
  const float to_rad = std::numbers::pi_v<float> / 180.f;
  for (int y = 0; y < normal_map.height; ++y)
    for (int x = 0; x < normal_map.width; ++x) {
      float* p = normal_map.pixel(x, y);
      if (p[3] <= 0) continue;
      const Eigen::Vector2f t = tilt_deg.at(x + 0.5f, y + 0.5f) * to_rad;
      // Turning about `up` by +t.x moves the camera-facing axis toward `right`; about `right` by
      // -t.y moves it toward `up`.
      const Eigen::Vector3f omega = t.x() * up - t.y() * right;
      const float angle = omega.norm();
      if (angle == 0) continue;
      encode_normal(p, Eigen::AngleAxisf(angle, omega / angle) * decode_normal(p));
    }
}

void shade_image(Image& rgba, const SmoothField& relative_gain) {
  require(rgba.channels == 4, "view images must be RGBA");
  for (int y = 0; y < rgba.height; ++y)
    for (int x = 0; x < rgba.width; ++x) {
      float* p = rgba.pixel(x, y);
      const float gain = 1 + relative_gain.at(x + 0.5f, y + 0.5f).x();
      for (int c = 0; c < 3; ++c) p[c] = std::clamp(p[c] * gain, 0.f, 1.f);
    }
}

void rotate_normals(Image& normal_map, const Eigen::Vector3f& axis, float degrees) {
  Eigen::Matrix3f r = Eigen::AngleAxisf(degrees * std::numbers::pi_v<float> / 180.f, axis.normalized()).toRotationMatrix();
  for (size_t i = 0; i < normal_map.pixel_count(); ++i) {
    float* p = normal_map.data.data() + i * normal_map.channels;
    if (p[3] <= 0) continue;
    encode_normal(p, r * decode_normal(p));
  }
}

void add_normal_noise(Image& normal_map, float sigma, uint64_t seed) {
  require(sigma >= 0, "normal noise must not be negative, got " + std::to_string(sigma));
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.f, sigma);
  for (size_t i = 0; i < normal_map.pixel_count(); ++i) {
    float* p = normal_map.data.data() + i * normal_map.channels;
    if (p[3] <= 0) continue;
    Vec3f n = decode_normal(p) + Vec3f(noise(rng), noise(rng), noise(rng));
    if (n.norm() > 0) encode_normal(p, n.normalized());
  }
}

void perturb_view_set(const fs::path& in_dir, const fs::path& out_dir, const PerturbOptions& options) {
  require(path_exists(in_dir) && fs::is_directory(in_dir), "view folder " + in_dir.string() + " does not exist");
  require(fs::absolute(in_dir).lexically_normal() != fs::absolute(out_dir).lexically_normal(),
          "output folder must differ from the input folder " + in_dir.string());
  // Every input is read and perturbed before the first output is written, so a bad file leaves no
  // partial output folder behind.
  struct Output {
    std::string name;
    Image image;
    int bit_depth;
  };
  std::vector<Output> outputs;
  for (View v : kAllViews) {
    const std::string name = view_name(v);
    const ViewWarp& warp = options.warps[int(v)];
    const fs::path rgb_path = in_dir / (name + "_rgb.png"), normal_path = in_dir / (name + "_normal.png");
    // The front view stands for the input photo: only the generated views are displaced and shaded.
    const bool generated = v != View::Front;
    const SmoothField displacement(options.displacement, field_seed(options.seed, 0, v));
    if (path_exists(rgb_path)) {
      Image rgb = load_image_rgba(rgb_path);
      if (!warp.identity()) rgb = warp_image(rgb, warp, false);
      if (generated && options.displacement.active()) rgb = displace_image(rgb, displacement, false);
      if (generated && options.shading.active())
        shade_image(rgb, SmoothField(options.shading, field_seed(options.seed, 2, v)));
      outputs.push_back({rgb_path.filename().string(), std::move(rgb), 8});
    }
    if (path_exists(normal_path)) {
      Image normal = load_image_rgba(normal_path);
      if (!warp.identity()) {
        normal = warp_image(normal, warp, true);
        // Rolling the picture rolls the object about the viewing axis: turn the normals alike.
        Eigen::Vector3f axis = options.normal_space == NormalSpace::World ? view_camera(v, 16).toward_camera()
                                                                           : Eigen::Vector3f::UnitZ();
        rotate_normals(normal, axis, warp.rotate_deg);
      }
      if (generated && options.displacement.active()) normal = displace_image(normal, displacement, true);
      if (options.bend.active()) {
        const Eigen::Matrix3f to_camera = view_camera(v, 16).rotation();
        const bool world = options.normal_space == NormalSpace::World;
        bend_normals(normal, SmoothField(options.bend, field_seed(options.seed, 1, v)),
                     world ? Eigen::Vector3f(to_camera.row(0)) : Eigen::Vector3f::UnitX(),
                     world ? Eigen::Vector3f(to_camera.row(1)) : Eigen::Vector3f::UnitY());
      }
      // One stream per view, so a view's noise does not depend on which other views exist.
      if (options.normal_noise > 0) add_normal_noise(normal, options.normal_noise, options.seed * 4 + int(v));
      outputs.push_back({normal_path.filename().string(), std::move(normal), 16});
    }
  }
  require(!outputs.empty(), "view folder " + in_dir.string() +
                                " holds no <view>_rgb.png or <view>_normal.png (front, right, back, left)");
  std::vector<fs::path> companions;  // other files of the set (e.g. a ground-truth mesh), copied along
  for (const auto& entry : fs::directory_iterator(in_dir)) {
    const std::string name = entry.path().filename().string();
    const bool view_file = std::any_of(outputs.begin(), outputs.end(), [&](const Output& o) { return o.name == name; });
    std::error_code ec;  // a companion that is not a readable file (a dangling link, a loop) is not copied
    if (entry.is_regular_file(ec) && name != "perturbation.json" && !view_file) companions.push_back(entry.path());
  }

  ensure_directory(out_dir);
  for (const Output& o : outputs) save_image(o.image, out_dir / o.name, o.bit_depth);
  for (const fs::path& path : companions)
    write_atomically(out_dir / path.filename(), [&](const fs::path& tmp) { fs::copy_file(path, tmp); });
  nlohmann::json record;
  record["source"] = in_dir.string();
  record["seed"] = options.seed;
  record["normal_noise"] = options.normal_noise;
  for (const auto& [name, spec] : {std::pair<const char*, const SmoothFieldSpec&>{"displacement_px", options.displacement},
                                   {"bend_deg", options.bend},
                                   {"shading", options.shading}})
    record[name] = {{"amplitude", spec.amplitude}, {"scale_px", spec.scale_px}};
  record["normal_space"] = options.normal_space == NormalSpace::World ? "world" : "camera";
  for (View v : kAllViews)
    record["views"][view_name(v)] = {{"rotate_deg", options.warps[int(v)].rotate_deg},
                                     {"scale", options.warps[int(v)].scale}};
  write_atomically(out_dir / "perturbation.json", [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << record.dump(2) << "\n";
    require(bool(f), "cannot write " + (out_dir / "perturbation.json").string());
  });
}

}  // namespace u3d
