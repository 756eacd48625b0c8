#pragma once
// Controlled inconsistency between the four views of a view set (docs/evaluation.md, "Perturbation"):
// one view rolled or zoomed relative to the others, and noise on the normal maps. Used to measure how
// gracefully reconstruction degrades when the generated views disagree, as real diffusion outputs do.
#include <array>
#include <cstdint>
#include <filesystem>

#include "core/camera.h"
#include "core/image.h"
#include "render/shade.h"

namespace u3d {

struct ViewWarp {
  float rotate_deg = 0;  // in-plane rotation about the image centre, counter-clockwise as seen
  float scale = 1;       // zoom about the image centre (> 1 enlarges the object)
  bool identity() const { return rotate_deg == 0 && scale == 1; }
};

struct PerturbOptions {
  std::array<ViewWarp, 4> warps;  // indexed by View
  float normal_noise = 0;         // standard deviation of Gaussian noise per normal component
  uint64_t seed = 0;
  NormalSpace normal_space = NormalSpace::World;  // how the input normal maps are encoded
};

// Resamples an RGBA image under the warp: bilinear on alpha-premultiplied colour (no dark fringes),
// transparent outside the source. When `unit_vectors` is set, RGB encodes normals: the interpolated
// vectors are renormalized.
Image warp_image(const Image& rgba, const ViewWarp& warp, bool unit_vectors);

// Turns the normals of a normal map (RGB = (n + 1) / 2) about `axis` by `degrees` (right-hand rule).
void rotate_normals(Image& normal_map, const Eigen::Vector3f& axis, float degrees);

// Adds N(0, sigma^2) to every component of every covered normal and renormalizes. Deterministic per seed.
void add_normal_noise(Image& normal_map, float sigma, uint64_t seed);

// Reads <view>_rgb.png / <view>_normal.png from in_dir (a view may lack either file, but the set must
// hold at least one), writes the perturbed files to out_dir, copies other files unchanged and records
// the options in out_dir/perturbation.json. A rolled view's normals are turned with it, so the view
// stays a self-consistent picture of a rolled object. Throws Error on a missing or empty in_dir.
void perturb_view_set(const std::filesystem::path& in_dir, const std::filesystem::path& out_dir,
                      const PerturbOptions& options);

}  // namespace u3d
