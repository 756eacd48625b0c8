// The official front-photo preparation: Pillow's thumbnail size, the white background with the alpha kept,
// simple_preprocess's crop and square, the rule that photos at most 512 px wide are super-resolved, an
// opaque alpha taken as none, and matte_photo's cut-out with the solid mask.
#include <gtest/gtest.h>

#include <cmath>

#include "core/progress.h"
#include "core/solid_matte.h"
#include "golden.h"
#include "nn/pipelines/input_photo.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

// The tiny U^2-Net of the golden cases.
std::filesystem::path tiny_matting() { return golden_dir("u2net_tiny") / "u2net_div8" / "u2net_div8_op17.onnx"; }

TEST(InputPhoto, ThumbnailSizeKeepsTheAspectRatio) {
  EXPECT_EQ(thumbnail_size(100, 50, 2048), std::make_pair(int64_t{100}, int64_t{50}));
  EXPECT_EQ(thumbnail_size(2048, 2048, 2048), std::make_pair(int64_t{2048}, int64_t{2048}));
  EXPECT_EQ(thumbnail_size(4000, 3000, 2048), std::make_pair(int64_t{2048}, int64_t{1536}));
  EXPECT_EQ(thumbnail_size(3000, 4000, 2048), std::make_pair(int64_t{1536}, int64_t{2048}));
  // 3000 x 1999: 2048 / 1.50075 = 1364.65; 1365 gives the aspect closer to the image's than 1364.
  EXPECT_EQ(thumbnail_size(3000, 1999, 2048), std::make_pair(int64_t{2048}, int64_t{1365}));
}

TEST(InputPhoto, ColoursGoOnWhiteAndTheAlphaStays) {
  torch::Tensor rgba = torch::tensor({0, 0, 0, 0, 10, 20, 30, 255, 0, 100, 200, 128}, torch::kUInt8).view({1, 3, 4});
  const torch::Tensor out = colours_on_white(rgba);
  // transparent -> white; opaque unchanged; half: (v a + 255 (255 - a)) / 255 rounded.
  const torch::Tensor expected =
      torch::tensor({255, 255, 255, 0, 10, 20, 30, 255, 127, 177, 227, 128}, torch::kUInt8).view({1, 3, 4});
  EXPECT_TRUE(torch::equal(out, expected)) << out;
}

TEST(InputPhoto, SimplePreprocessCropsToTheAlphaBoxAndPadsToASquare) {
  torch::Tensor rgba = torch::zeros({10, 20, 4}, torch::kUInt8);
  rgba.slice(2, 0, 3).fill_(50);
  rgba.slice(0, 2, 6).slice(1, 3, 13).select(2, 3).fill_(200);  // rows 2..5, columns 3..12
  rgba[7][15][3] = 60;                                          // not above the threshold
  const torch::Tensor out = simple_preprocess(rgba);
  // The official slice ends before the box's last row and column: rows 2..4, columns 3..11 (3 x 9),
  // centred in a 9 x 9 square of (255, 255, 255, 0) from row (9 - 3) / 2 = 3.
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{9, 9, 4}));
  EXPECT_TRUE(torch::equal(out.slice(0, 3, 6), rgba.slice(0, 2, 5).slice(1, 3, 12)));
  for (const torch::Tensor& pad : {out.slice(0, 0, 3), out.slice(0, 6, 9)}) {
    EXPECT_TRUE((pad.slice(2, 0, 3) == 255).all().item<bool>());
    EXPECT_TRUE((pad.select(2, 3) == 0).all().item<bool>());
  }
  EXPECT_THROW(simple_preprocess(torch::zeros({4, 4, 4}, torch::kUInt8)), u3d::Error);
}

// An RRDBNet that upscales by pixel repetition: each conv passes channel c to channel c through its centre
// tap, the dense blocks and conv_body add nothing.
RRDBNet nearest_neighbour_rrdbnet() {
  RRDBNetConfig config;
  config.num_feat = 3;
  config.num_block = 1;
  config.num_grow = 2;
  RRDBNet net(config, torch::TensorOptions());
  torch::NoGradGuard no_grad;
  for (auto& p : net->parameters()) p.zero_();
  for (Conv2d conv : {net->conv_first, net->conv_up1, net->conv_up2, net->conv_hr, net->conv_last})
    for (int c = 0; c < 3; ++c) conv->weight[c][c][1][1] = 1.0f;
  return net;
}

TEST(InputPhoto, OnlyPhotosAtMost512PxWideAreSuperResolved) {
  set_progress_quiet(true);
  int upscaler_loads = 0, matting_loads = 0;
  const InputPhotoModels models{
      [&] {
        ++upscaler_loads;
        auto upscaler = std::make_unique<UpscaleModel>();
        upscaler->net = nearest_neighbour_rrdbnet();
        return upscaler;
      },
      [&] {
        ++matting_loads;
        return MattingModel::load(tiny_matting(), Precision::kFp32);
      }};
  // A photo with a real alpha (so no background removal is forced): an opaque disc on transparency.
  auto photo = [](int64_t w, int64_t h) {
    torch::Tensor rgba = torch::full({h, w, 4}, 120, torch::kUInt8);
    const torch::Tensor ys = torch::arange(h).view({h, 1}) - h / 2, xs = torch::arange(w).view({1, w}) - w / 2;
    rgba.select(2, 3).copy_(((ys * ys + xs * xs) <= (h / 3) * (h / 3)).to(torch::kUInt8) * 255);
    return rgba;
  };
  // The disc (radius 8) is 17 px across, less the official crop's last row and column: 16. A photo 512 px
  // wide is upscaled x4 first (68 - 1), one 520 px wide is not.
  const torch::Tensor small = prepare_input_photo(photo(512, 24), models, false, false);
  const torch::Tensor large = prepare_input_photo(photo(520, 24), models, false, false);
  EXPECT_EQ(small.size(0), 67);
  EXPECT_EQ(large.size(0), 16);
  // Each network is loaded only when the photo needs it: one upscale, no background removal.
  EXPECT_EQ(upscaler_loads, 1);
  EXPECT_EQ(matting_loads, 0);
  // The colours are kept under the alpha.
  EXPECT_EQ(large[8][8][0].item<int>(), 120);
}

// A photo whose alpha is 255 everywhere is a photo without alpha: its background is removed, and it is
// prepared exactly as its RGB channels alone are, although the upscaler (the tiny random Real-ESRGAN)
// would not keep its alpha at 255.
TEST(InputPhoto, AnOpaqueAlphaIsPreparedAsNoAlpha) {
  set_progress_quiet(true);
  int matting_loads = 0;
  const std::filesystem::path upscaler = golden_dir("realesrgan_tiny") / "rrdbnet_tiny_op17.onnx";
  const InputPhotoModels models{[&] { return UpscaleModel::load(upscaler, Precision::kFp32); },
                                [&] {
                                  ++matting_loads;
                                  return MattingModel::load(tiny_matting(), Precision::kFp32);
                                }};
  torch::Tensor rgb = torch::full({96, 96, 3}, 140, torch::kUInt8);
  rgb.slice(0, 30, 70).slice(1, 25, 75).select(2, 0).fill_(230);
  const torch::Tensor rgba = torch::cat({rgb, torch::full({96, 96, 1}, 255, torch::kUInt8)}, 2);
  EXPECT_FALSE((UpscaleModel::load(upscaler, Precision::kFp32)->upscale(rgba).select(2, 3) == 255).all().item<bool>());
  EXPECT_TRUE(
      torch::equal(prepare_input_photo(rgba, models, false, false), prepare_input_photo(rgb, models, false, false)));
  EXPECT_EQ(matting_loads, 2);
}

// matte_photo is rembg's remove with the mask made solid: the cut-out of the photo with solid_matte of the
// network's mask, or with the mask itself for the raw matte.
TEST(InputPhoto, MattePhotoCutsOutWithTheSolidMask) {
  auto model = MattingModel::load(tiny_matting(), Precision::kFp32);
  const torch::Tensor rgb = golden_tensors("isnet_tiny", "inputs").at("image_rgb_u8");
  const torch::Tensor mask = model->matte(rgb).contiguous();
  EXPECT_TRUE(torch::equal(matte_photo(rgb, *model, /*raw_matte=*/true), cutout(rgb, mask, MattingStyle::kRembg)));

  Image alpha(int(mask.size(1)), int(mask.size(0)), 1);
  for (size_t i = 0; i < alpha.data.size(); ++i) alpha.data[i] = float(mask.data_ptr<uint8_t>()[i]) / 255.f;
  const Image solid = solid_matte(alpha);
  torch::Tensor solid_mask = torch::empty_like(mask);
  for (size_t i = 0; i < solid.data.size(); ++i)
    solid_mask.data_ptr<uint8_t>()[i] = static_cast<uint8_t>(std::lround(solid.data[i] * 255.f));
  EXPECT_FALSE(torch::equal(solid_mask, mask));  // the comparison below can tell the two apart
  EXPECT_TRUE(torch::equal(matte_photo(rgb, *model, false), cutout(rgb, solid_mask, MattingStyle::kRembg)));
}

}  // namespace
}  // namespace u3d::nn
