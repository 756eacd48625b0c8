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

}  // namespace

Image warp_image(const Image& src, const ViewWarp& warp, bool unit_vectors) {
  require(src.channels == 4, "view images must be RGBA");
  require(warp.scale > 0, "view scale must be positive, got " + std::to_string(warp.scale));
  Image out(src.width, src.height, 4, 0.f);
  const float theta = warp.rotate_deg * std::numbers::pi_v<float> / 180.f;
  const float c = std::cos(theta), s = std::sin(theta);
  const float cx = 0.5f * src.width, cy = 0.5f * src.height;
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      // Output offset in "up" coordinates, mapped back by the inverse rotation and scale.
      float u = (x + 0.5f - cx), v = (cy - (y + 0.5f));
      float su = (c * u + s * v) / warp.scale, sv = (-s * u + c * v) / warp.scale;
      float fx = cx + su - 0.5f, fy = cy - sv - 0.5f;  // continuous source pixel index
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
    if (path_exists(rgb_path)) {
      Image rgb = load_image_rgba(rgb_path);
      if (!warp.identity()) rgb = warp_image(rgb, warp, false);
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
