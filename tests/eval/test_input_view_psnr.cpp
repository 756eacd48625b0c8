// PSNR of a textured mesh against its input views (eval/input_view_psnr.h), on boxes whose views are
// exact: at 64 px a pixel is 1/32 wide, so a box with faces on multiples of 1/32 covers whole pixels
// (tests/core/synthetic_views.h), and a texture sampled at texel centres gives closed-form colours.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "core/error.h"
#include "core/synthetic_views.h"
#include "eval/image_metrics.h"
#include "eval/input_view_psnr.h"
#include "geometry/test_shapes.h"

namespace u3d {
namespace {

constexpr int kRes = 64;
constexpr float kPixel = 2.f / kRes;

// test::box_mesh's quads, in its order: -X, +X, -Y, +Y, -Z, +Z. The quad each view sees head-on:
constexpr int kQuadSeenBy[4] = {5, 1, 4, 0};  // front (+Z), right (+X), back (-Z), left (-X)

// The box with every quad's four corners its own vertices (so UVs may differ per quad), UV from
// uv(quad, corner position), and one material with `texture`.
Mesh textured_box(const Vec3f& lo, const Vec3f& hi, const Image& texture,
                  const std::function<Vec2f(int, const Vec3f&)>& uv) {
  const Mesh box = test::box_mesh(lo, hi);
  Mesh m;
  for (size_t f = 0; f < box.faces.size(); ++f) {
    Vec3i face;
    for (int c = 0; c < 3; ++c) {
      face[c] = int(m.positions.size());
      m.positions.push_back(box.positions[box.faces[f][c]]);
      m.uvs.push_back(uv(int(f / 2), m.positions.back()));
    }
    m.faces.push_back(face);
  }
  m.materials.push_back({"box", Vec4f::Ones(), texture});
  return m;
}

// One colour per quad (multiples of 1/8: exact through the supersampling's sums).
Vec3f quad_color(int quad) { return Vec3f(float(quad + 1) / 8.f, float(7 - quad) / 8.f, 0.25f); }

// A 6 x 1 texture holding `colors` and a box whose quads each sample their texel's centre.
Mesh box_with_quad_colors(const Vec3f& lo, const Vec3f& hi, const std::array<Vec3f, 6>& colors) {
  Image texture(6, 1, 3);
  for (int q = 0; q < 6; ++q)
    for (int c = 0; c < 3; ++c) texture.at(q, 0, c) = colors[q][c];
  return textured_box(lo, hi, texture, [](int quad, const Vec3f&) { return Vec2f((quad + 0.5f) / 6.f, 0.5f); });
}

// The exact views of a box, each view's mask painted with the colour of the quad it sees.
ViewSet painted_views(const testing::Box& box) {
  ViewSet views = testing::boxes_views({box}, kRes);
  for (View v : kAllViews) {
    Image& rgb = views[v].rgb;
    const Vec3f color = quad_color(kQuadSeenBy[size_t(v)]);
    for (size_t p = 0; p < rgb.pixel_count(); ++p)
      if (is_foreground(rgb.data[4 * p + 3]))
        for (int c = 0; c < 3; ++c) rgb.data[4 * p + c] = color[c];
  }
  return views;
}

std::array<Vec3f, 6> quad_colors() {
  std::array<Vec3f, 6> colors;
  for (int q = 0; q < 6; ++q) colors[q] = quad_color(q);
  return colors;
}

double psnr_of_mse(double mse) { return -10.0 * std::log10(mse); }

const testing::Box kUnitBox{Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f)};

TEST(InputViewPsnr, TheRightTextureReproducesItsViews) {
  const ViewSet views = painted_views(kUnitBox);
  const InputViewPsnr p = input_view_psnr(box_with_quad_colors(kUnitBox.first, kUnitBox.second, quad_colors()), views, 2);
  EXPECT_EQ(p.ssaa, 2);
  for (View v : kAllViews) {
    EXPECT_EQ(p.pixels[size_t(v)], 32u * 32u) << view_name(v);
    EXPECT_EQ(p.views[size_t(v)], kPsnrCapDb) << view_name(v);
  }
  EXPECT_EQ(p.mean, kPsnrCapDb);
}

TEST(InputViewPsnr, AWrongTextureScoresAsItsColourErrorSays) {
  const ViewSet views = painted_views(kUnitBox);
  std::array<Vec3f, 6> swapped = quad_colors();
  std::swap(swapped[5], swapped[4]);  // front and back exchanged
  const InputViewPsnr p = input_view_psnr(box_with_quad_colors(kUnitBox.first, kUnitBox.second, swapped), views, 2);
  const double expected = psnr_of_mse((quad_color(5) - quad_color(4)).squaredNorm() / 3.0);  // 22.04 dB
  EXPECT_NEAR(p.views[size_t(View::Front)], expected, 1e-4);
  EXPECT_NEAR(p.views[size_t(View::Back)], expected, 1e-4);
  EXPECT_EQ(p.views[size_t(View::Right)], kPsnrCapDb);
  EXPECT_EQ(p.views[size_t(View::Left)], kPsnrCapDb);
  EXPECT_NEAR(p.mean, (2 * kPsnrCapDb + 2 * expected) / 4, 1e-4);
}

TEST(InputViewPsnr, OnlyPixelsInBothMasksCount) {
  // The views' box reaches 8 px further right than the mesh: of the front and back masks' 40 x 32 px,
  // the 32 x 32 the mesh covers are compared (the rest is a geometry error, not the texture's).
  const testing::Box wider{kUnitBox.first, Vec3f(0.5f + 8 * kPixel, 0.5f, 0.5f)};
  std::array<Vec3f, 6> swapped = quad_colors();
  std::swap(swapped[5], swapped[4]);
  const InputViewPsnr p =
      input_view_psnr(box_with_quad_colors(kUnitBox.first, kUnitBox.second, swapped), painted_views(wider), 2);
  const double expected = psnr_of_mse((quad_color(5) - quad_color(4)).squaredNorm() / 3.0);
  for (View v : {View::Front, View::Back}) {
    EXPECT_EQ(p.pixels[size_t(v)], 32u * 32u) << view_name(v);
    EXPECT_NEAR(p.views[size_t(v)], expected, 1e-4) << view_name(v);
  }
  EXPECT_EQ(p.pixels[size_t(View::Right)], 32u * 32u);
  EXPECT_EQ(p.views[size_t(View::Right)], kPsnrCapDb);
  // The other way round: the mesh's extra 8 columns lie over the views' background, outside the masks.
  const InputViewPsnr over =
      input_view_psnr(box_with_quad_colors(wider.first, wider.second, quad_colors()), painted_views(kUnitBox), 2);
  EXPECT_EQ(over.pixels[size_t(View::Front)], 32u * 32u);
  EXPECT_EQ(over.mean, kPsnrCapDb);
  // A mesh no view sees over its mask: nothing to compare, 0 dB.
  const Vec3f far = Vec3f(0.5f + 16 * kPixel, 0.5f + 16 * kPixel, 0.5f + 16 * kPixel);
  const InputViewPsnr off =
      input_view_psnr(box_with_quad_colors(far, far + Vec3f::Constant(4 * kPixel), quad_colors()), painted_views(kUnitBox), 2);
  EXPECT_EQ(off.pixels[size_t(View::Front)], 0u);
  EXPECT_EQ(off.mean, 0.0);
}

TEST(InputViewPsnr, SeesATextureCoarserThanTheViews) {
  // The front view: 1 px stripes, alternately 0.2 and 0.8 gray; the other views plain.
  const float dark = 0.2f, light = 0.8f;
  ViewSet views = testing::boxes_views({kUnitBox}, kRes);
  Image& front = views[View::Front].rgb;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x)
      if (is_foreground(front.at(x, y, 3)))
        for (int c = 0; c < 3; ++c) front.at(x, y, c) = x % 2 ? light : dark;
  // The front quad's texture: `texels` across its 32 pixels, averaging the stripes over each texel's
  // width (all of them at 32 texels, none at 16); the other quads sample the last texel, plain 0.5.
  auto front_psnr = [&](int texels, int ssaa) {
    Image texture(texels + 1, 1, 3, 0.5f);
    const int per_texel = 32 / texels;
    for (int t = 0; t < texels; ++t) {
      float sum = 0;
      for (int i = 0; i < per_texel; ++i) sum += (16 + t * per_texel + i) % 2 ? light : dark;
      for (int c = 0; c < 3; ++c) texture.at(t, 0, c) = sum / float(per_texel);
    }
    const float width = float(texels + 1);
    const Mesh box = textured_box(kUnitBox.first, kUnitBox.second, texture, [&](int quad, const Vec3f& p) {
      return quad == kQuadSeenBy[0] ? Vec2f((p.x() + 0.5f) * float(texels) / width, 0.5f)
                                     : Vec2f((float(texels) + 0.5f) / width, 0.5f);
    });
    return input_view_psnr(box, views, ssaa).views[size_t(View::Front)];
  };
  // Without supersampling the pixel centres fall on texel centres: the stripes come back exactly.
  EXPECT_GT(front_psnr(32, 1), 60.0);
  // With 2 x 2 samples a pixel's samples lie a quarter pixel off its centre: 3/4 of the pixel's own
  // stripe, 1/4 of its neighbours' (within a texel of the quad's borders, the texture clamps), so the error is
  // 0.25 * 0.6 = 0.15 on most pixels; the coarse texture is flat 0.5, an error of 0.3 everywhere.
  const double fine = front_psnr(32, 2), coarse = front_psnr(16, 2);
  EXPECT_NEAR(coarse, psnr_of_mse(0.3 * 0.3), 1e-3);  // 10.46 dB
  EXPECT_GT(fine, psnr_of_mse(0.16 * 0.16));
  EXPECT_GT(fine, coarse + 5.0);
}

TEST(InputViewPsnr, RejectsABadSupersamplingFactor) {
  const ViewSet views = painted_views(kUnitBox);
  const Mesh box = box_with_quad_colors(kUnitBox.first, kUnitBox.second, quad_colors());
  EXPECT_THROW(input_view_psnr(box, views, 0), Error);
  EXPECT_THROW(input_view_psnr(box, views, 9), Error);
}

}  // namespace
}  // namespace u3d
