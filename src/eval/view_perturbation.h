#pragma once
// Controlled inconsistency between the four views of a view set (docs/evaluation.md, "Perturbation"):
// one view rolled or zoomed relative to the others, noise on the normal maps, and the smooth local
// disagreements that multi-view diffusion produces (a displacement field per generated view, a
// low-frequency bend of every normal map, slight shading differences between the colour views).
// Used to measure how gracefully reconstruction degrades when the generated views disagree.
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

// A smooth random field over an image: `amplitude` is the RMS of each component over the plane,
// `scale_px` the wavelength of its sinusoidal modes in pixels (0 amplitude = off).
struct SmoothFieldSpec {
  float amplitude = 0;
  float scale_px = 0;
  bool active() const { return amplitude != 0; }
};

struct PerturbOptions {
  std::array<ViewWarp, 4> warps;  // indexed by View
  float normal_noise = 0;         // standard deviation of Gaussian noise per normal component
  // Models of named multi-view diffusion failures (docs/evaluation.md), each drawn independently
  // per view from `seed`:
  SmoothFieldSpec displacement;  // pixels; the generated views (right, back, left), both images
  SmoothFieldSpec bend;          // degrees of normal tilt; all four normal maps
  SmoothFieldSpec shading;       // relative brightness change; the generated views' colour images
  uint64_t seed = 0;
  NormalSpace normal_space = NormalSpace::World;  // how the input normal maps are encoded
};

// Two independent smooth scalar fields over the image plane, each a sum of sinusoids of wavelength
// scale_px with random directions and phases, scaled to RMS `amplitude` over the plane.
class SmoothField {
 public:
  SmoothField(const SmoothFieldSpec& spec, uint64_t seed);
  Eigen::Vector2f at(float x, float y) const;  // pixel coordinates

 private:
  static constexpr int kModes = 8;
  std::array<Eigen::Vector2f, 2 * kModes> wave_;  // angular wave vectors, first kModes for x
  std::array<float, 2 * kModes> phase_;
  float mode_amplitude_ = 0;
};

// out(p) = src(p - d(p)): the picture moved locally by the displacement field d (pixels, x right,
// y down), resampled as warp_image does.
Image displace_image(const Image& rgba, const SmoothField& displacement, bool unit_vectors);

// Tilts every covered normal by the field's angle (degrees): the x component turns normals toward
// the picture's right (about the picture's up axis), the y component toward its top. `right` and
// `up` are the picture's axes in the space the map encodes normals in.
void bend_normals(Image& normal_map, const SmoothField& tilt_deg, const Eigen::Vector3f& right,
                  const Eigen::Vector3f& up);

// Multiplies the RGB of every pixel by (1 + s(p)), s the field's x component, clamped to [0, 1].
void shade_image(Image& rgba, const SmoothField& relative_gain);

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
