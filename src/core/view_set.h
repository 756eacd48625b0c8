#pragma once
// A view set: the four orthographic views (front, right, back, left) that ISOMER reconstructs from and
// that `unique3d render` writes, each an RGB image and a normal map. Its folder layout:
//   VIEWS_DIR/{front,right,back,left}_{rgb,normal}.png
// Images are square PNGs (8 or 16 bit); RGB and normal maps may differ in resolution, but all RGB
// images share one size and all normal maps share one size.
//
// Masks. The alpha channel is the mask (foreground where alpha >= 0.5). When a file has no alpha:
//   - a normal map takes the alpha of its view's RGB image if that has one; otherwise a pixel is
//     foreground when its decoded vector (2 * rgb - 1) has a length in [0.6, 1.4] (black, white and
//     mid-grey backgrounds all fall outside, real unit normals inside);
//   - an RGB image takes its view's normal-map mask (resized to its resolution).
//
// Normal maps encode n as (n + 1) / 2 in world space (default) or in the view's camera space
// (x right, y up, z toward the camera; --normal-space camera). They are decoded to world-space unit
// vectors at load time, so everything downstream sees world normals.
#include <array>
#include <filesystem>
#include <string>

#include "core/camera.h"
#include "core/image.h"

namespace u3d {

// Parses "world" / "camera"; throws Error otherwise.
NormalSpace parse_normal_space(const std::string& text);

struct ViewImages {
  Image rgb;      // 4 channels: sRGB colour, alpha = mask weight in [0, 1]
  Image normals;  // 4 channels: world-space unit normal (x, y, z), mask in {0, 1}
};

struct ViewSet {
  std::array<ViewImages, 4> views;  // indexed by int(View)

  const ViewImages& operator[](View v) const { return views[size_t(v)]; }
  ViewImages& operator[](View v) { return views[size_t(v)]; }
  int rgb_resolution() const { return views[0].rgb.width; }
  int normal_resolution() const { return views[0].normals.width; }
};

// File name of a view's image inside VIEWS_DIR, e.g. "front_rgb.png".
std::string view_file_name(View v, bool normal);

// How strictly the content of normal maps is checked. kGiven: maps someone made (files, renders);
// most foreground pixels must decode to unit vectors and face their camera, else the maps are in the
// other space or encoding, an Error. kPredicted: maps a network drew, where failing those tests means
// a poor prediction, not a mistake: a warning through progress(), and the maps are used as they are.
enum class NormalCheck { kGiven, kPredicted };

// Loads and validates VIEWS_DIR. Every problem (missing or non-PNG file, non-square or mismatched
// sizes, empty or full mask, all-black or non-normal normal map, NaN, normals facing away from their
// camera) is an Error naming the file, found before any work starts.
ViewSet load_view_set(const std::filesystem::path& dir, NormalSpace space = NormalSpace::World,
                      NormalCheck check = NormalCheck::kGiven);

// Builds a ViewSet from images already in memory (as loaded from the files: RGB(A) in [0, 1], normal
// maps encoded as (n + 1) / 2), applying the same mask rules and checks as load_view_set. `names`
// label the images in error messages.
ViewSet make_view_set(std::array<Image, 4> rgb, std::array<Image, 4> normal_maps, NormalSpace space,
                      const std::array<std::string, 4>& rgb_names, const std::array<std::string, 4>& normal_names,
                      NormalCheck check = NormalCheck::kGiven);

// Foreground test shared by every stage.
inline bool is_foreground(float mask) { return mask >= 0.5f; }

}  // namespace u3d
