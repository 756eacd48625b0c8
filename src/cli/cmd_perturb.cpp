// unique3d perturb VIEWS_DIR -o OUT_DIR: make the four views of a view set inconsistent on purpose.
#include <cmath>
#include <memory>

#include "cli/command.h"
#include "core/error.h"
#include "eval/view_perturbation.h"

namespace u3d::cli {
namespace {

struct PerturbArgs {
  std::string in_dir, out_dir, normal_space = "world";
  std::vector<std::string> rotations, scales;
  std::string warp, bend, shading;
  PerturbOptions options;
};

// "right:3" -> (View::Right, 3).
std::pair<View, float> parse_view_value(const std::string& spec, const char* option) {
  auto colon = spec.find(':');
  require(colon != std::string::npos, std::string(option) + " expects VIEW:VALUE (e.g. right:3), got '" + spec + "'");
  std::string name = spec.substr(0, colon), value = spec.substr(colon + 1);
  for (View v : kAllViews) {
    if (name != view_name(v)) continue;
    try {
      size_t used = 0;
      float x = std::stof(value, &used);
      require(used == value.size() && std::isfinite(x), "");
      return {v, x};
    } catch (const std::exception&) {
      throw Error(std::string(option) + ": '" + value + "' in '" + spec + "' is not a number");
    }
  }
  throw Error(std::string(option) + ": unknown view '" + name + "' in '" + spec + "' (front, right, back, left)");
}

// "2:64" -> amplitude 2, scale 64 ("" = off).
SmoothFieldSpec parse_field(const std::string& spec, const char* option, const char* amplitude_name) {
  if (spec.empty()) return {};
  const std::string usage = std::string(option) + " expects " + amplitude_name + ":SCALE_PX (e.g. 2:64), got '" + spec + "'";
  const auto colon = spec.find(':');
  require(colon != std::string::npos, usage);
  auto number = [&](const std::string& text) {
    try {
      size_t used = 0;
      const float x = std::stof(text, &used);
      require(used == text.size() && std::isfinite(x), "");
      return x;
    } catch (const std::exception&) {
      throw Error(usage);
    }
  };
  const SmoothFieldSpec out{number(spec.substr(0, colon)), number(spec.substr(colon + 1))};
  require(out.amplitude >= 0, std::string(option) + ": the amplitude must not be negative in '" + spec + "'");
  require(out.scale_px > 0, std::string(option) + ": the scale must be positive in '" + spec + "'");
  return out;
}

void run_perturb(PerturbArgs& a) {
  a.options.displacement = parse_field(a.warp, "--warp", "AMPLITUDE_PX");
  a.options.bend = parse_field(a.bend, "--bend", "DEGREES");
  a.options.shading = parse_field(a.shading, "--shading", "AMPLITUDE");
  require(a.options.shading.amplitude < 1, "--shading: the amplitude must be below 1 (a relative brightness change)");
  for (const auto& spec : a.rotations) {
    auto [v, deg] = parse_view_value(spec, "--rotate-view");
    a.options.warps[int(v)].rotate_deg = deg;
  }
  for (const auto& spec : a.scales) {
    auto [v, s] = parse_view_value(spec, "--scale-view");
    require(s > 0, "--scale-view: scale must be positive in '" + spec + "'");
    a.options.warps[int(v)].scale = s;
  }
  a.options.normal_space = a.normal_space == "camera" ? NormalSpace::Camera : NormalSpace::World;
  perturb_view_set(a.in_dir, a.out_dir, a.options);
}

const CommandRegistration registration{
    "perturb", "Make the four views of a view set inconsistent in controlled, reproducible ways",
    [](CLI::App& sub) -> CommandAction {
      auto a = std::make_shared<PerturbArgs>();
      sub.add_option("views", a->in_dir, "Folder with <view>_rgb.png / <view>_normal.png")->required();
      sub.add_option("-o,--output", a->out_dir, "Output folder")->required();
      sub.add_option("--rotate-view", a->rotations, "VIEW:DEGREES in-plane roll (counter-clockwise), repeatable");
      sub.add_option("--scale-view", a->scales, "VIEW:FACTOR zoom about the image centre, repeatable");
      sub.add_option("--normal-noise", a->options.normal_noise, "Std. deviation of Gaussian noise per normal component")
          ->check(number_in(0, 10));
      sub.add_option("--warp", a->warp,
                     "AMPLITUDE_PX:SCALE_PX smooth displacement field (RMS pixels, wavelength pixels) of each "
                     "generated view (right, back, left): parts drawn slightly off where the other views put them");
      sub.add_option("--bend", a->bend,
                     "DEGREES:SCALE_PX low-frequency tilt (RMS degrees, wavelength pixels) of every normal map: "
                     "surfaces predicted flatter or rounder than they are, differently per view");
      sub.add_option("--shading", a->shading,
                     "AMPLITUDE:SCALE_PX smooth relative brightness change (RMS, wavelength pixels) of each "
                     "generated colour view: lighting baked in differently per view");
      sub.add_option("--seed", a->options.seed, "Seed of the normal noise and of the smooth fields")->capture_default_str();
      sub.add_option("--normal-space", a->normal_space, "Encoding of the input normal maps")
          ->check(CLI::IsMember({"world", "camera"}))->capture_default_str();
      return [a] { run_perturb(*a); };
    }};

}  // namespace
}  // namespace u3d::cli
