// Agreement of a mesh with the masks of its input views (eval/mask_agreement.h), on cases whose pixel
// counts follow from the geometry: at 64 px a pixel is 1/32 wide, so boxes with faces on multiples of
// 1/32 cover whole pixels, and their views (tests/core/synthetic_views.h) are exact.
#include <gtest/gtest.h>

#include "core/synthetic_views.h"
#include "eval/mask_agreement.h"
#include "geometry/test_shapes.h"

namespace u3d {
namespace {

constexpr int kRes = 64;
constexpr float kPixel = 2.f / kRes;

// Both meshes' faces and vertices in one mesh (separate pieces).
Mesh joined(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  const int offset = int(m.positions.size());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (const Vec3i& f : b.faces) m.faces.push_back(f + Vec3i::Constant(offset));
  return m;
}

MaskAgreementOptions grid_at_view_resolution() {
  MaskAgreementOptions options;
  options.hull_resolution = kRes;
  return options;
}

// `image` (a 20 x 20 coverage image) with a w x h block of pixels from (x0, y0) set.
std::vector<uint8_t> block(int x0, int y0, int w, int h, std::vector<uint8_t> image = std::vector<uint8_t>(400, 0)) {
  for (int y = y0; y < y0 + h; ++y)
    for (int x = x0; x < x0 + w; ++x) image[size_t(y) * 20 + size_t(x)] = 1;
  return image;
}

TEST(MaskAgreement, OnlyPixelsBeyondTheToleranceCount) {
  const std::vector<uint8_t> mask = block(4, 4, 8, 8);
  // The mesh overhangs the mask's right side by 4 columns (1, 2, 3 and 4 px from the mask) over 5 rows.
  const std::vector<uint8_t> mesh = block(12, 6, 4, 5, mask);
  const ViewMaskAgreement a = compare_coverage(mesh, mask, 20, 20, 2.f);
  EXPECT_EQ(a.mask_pixels, 64u);
  EXPECT_EQ(a.mesh_pixels, 64u + 20u);
  EXPECT_EQ(a.spurious.pixels, 10u);  // the columns 3 and 4 px away
  EXPECT_EQ(a.spurious.blobs, 1u);
  EXPECT_EQ(a.spurious.largest_blob, 10u);
  EXPECT_EQ(a.missing.pixels, 0u);
  // A corner pixel two columns and two rows off lies sqrt(8) px away: beyond 2 px.
  const ViewMaskAgreement corner = compare_coverage(block(13, 13, 1, 1, mask), mask, 20, 20, 2.f);
  EXPECT_EQ(corner.spurious.pixels, 1u);
  // Without tolerance every pixel off the mask counts.
  EXPECT_EQ(compare_coverage(mesh, mask, 20, 20, 0.f).spurious.pixels, 20u);
}

TEST(MaskAgreement, SeparateBlobsAreCountedApartAndAMissingPartToo) {
  const std::vector<uint8_t> mask = block(2, 2, 6, 16);
  std::vector<uint8_t> mesh = block(2, 2, 6, 10);  // misses the mask's lowest 6 rows
  mesh = block(14, 2, 3, 2, mesh);                 // one blob of 6 pixels
  mesh = block(15, 10, 2, 2, mesh);                // one of 4
  const ViewMaskAgreement a = compare_coverage(mesh, mask, 20, 20, 2.f);
  EXPECT_EQ(a.spurious.pixels, 10u);
  EXPECT_EQ(a.spurious.blobs, 2u);
  EXPECT_EQ(a.spurious.largest_blob, 6u);
  EXPECT_EQ(a.missing.pixels, 4u * 6u);  // rows 3 to 6 below the mesh
  EXPECT_EQ(a.missing.blobs, 1u);
  EXPECT_EQ(a.missing.largest_blob, 24u);
}

TEST(MaskAgreement, AnExactMeshAgreesEverywhere) {
  const testing::Box box{Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f)};
  const ViewSet views = testing::boxes_views({box}, kRes);
  const MaskAgreement a = mask_agreement(test::box_mesh(box.first, box.second), views, grid_at_view_resolution());
  for (const ViewMaskAgreement& v : a.views) {
    EXPECT_EQ(v.mask_pixels, 32u * 32u);
    EXPECT_EQ(v.mesh_pixels, 32u * 32u);
    EXPECT_EQ(v.spurious.pixels, 0u);
    EXPECT_EQ(v.missing.pixels, 0u);
  }
  EXPECT_EQ(a.mesh_components, 1);
  EXPECT_EQ(a.hull_components, 1);
}

TEST(MaskAgreement, FindsASliverOverTheBackground) {
  const testing::Box box{Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f)};
  const ViewSet views = testing::boxes_views({box}, kRes);
  // A band 16 px wide, 2 px tall and 2 px deep, 5 px above the box (as spot's band over its horns).
  const Mesh sliver = test::box_mesh(Vec3f(-0.25f, 20 * kPixel, -kPixel), Vec3f(0.25f, 22 * kPixel, kPixel));
  const MaskAgreement a =
      mask_agreement(joined(test::box_mesh(box.first, box.second), sliver), views, grid_at_view_resolution());
  for (View v : kAllViews) {
    const ViewMaskAgreement& m = a.views[size_t(v)];
    const size_t band = v == View::Front || v == View::Back ? 16u * 2u : 2u * 2u;
    EXPECT_EQ(m.spurious.pixels, band) << view_name(v);
    EXPECT_EQ(m.spurious.blobs, 1u) << view_name(v);
    EXPECT_EQ(m.spurious.largest_blob, band) << view_name(v);
    EXPECT_EQ(m.missing.pixels, 0u) << view_name(v);
  }
  EXPECT_EQ(a.mesh_components, 2);
  EXPECT_EQ(a.hull_components, 1);
}

TEST(MaskAgreement, FindsAMissingPartAndTheHullsPieces) {
  const testing::Box box{Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f)};
  // A second box 8 x 16 x 8 px, 5 px right of the first: the side views see it inside the first box.
  const testing::Box part{Vec3f(20 * kPixel, -0.25f, -0.125f), Vec3f(28 * kPixel, 0.25f, 0.125f)};
  const ViewSet views = testing::boxes_views({box, part}, kRes);
  const MaskAgreement a = mask_agreement(test::box_mesh(box.first, box.second), views, grid_at_view_resolution());
  for (View v : kAllViews) {
    const ViewMaskAgreement& m = a.views[size_t(v)];
    const size_t missing = v == View::Front || v == View::Back ? 8u * 16u : 0u;
    EXPECT_EQ(m.missing.pixels, missing) << view_name(v);
    EXPECT_EQ(m.missing.blobs, missing ? 1u : 0u) << view_name(v);
    EXPECT_EQ(m.missing.largest_blob, missing) << view_name(v);
    EXPECT_EQ(m.spurious.pixels, 0u) << view_name(v);
  }
  EXPECT_EQ(a.mesh_components, 1);
  EXPECT_EQ(a.hull_components, 2);  // the masks keep the part apart from the box
}

}  // namespace
}  // namespace u3d
