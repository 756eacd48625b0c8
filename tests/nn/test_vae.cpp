#include "nn/models/vae.h"

#include <gtest/gtest.h>

#include "golden.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

// Tiled vs plain decode of the tiny golden VAE (random weights, outputs up to 2.5). Measured with tiles
// 8 / 10 / 12 at overlap 0.25 / 0.5 / 0.25: max abs 1.74 / 0.81 / 1.03, mean abs 0.21 / 0.11 / 0.11. The
// tiny random VAE is far more sensitive to per-tile GroupNorm statistics than a trained one.
constexpr double kTiledMaxError = 2.5;
constexpr double kTiledMeanError = 0.3;

TEST(Vae, MatchesDiffusersEncodeDecode) {
  torch::NoGradGuard no_grad;
  auto config = AutoencoderKLConfig::from_json(golden_config("vae"), "vae/config.json");
  AutoencoderKL vae(config, torch::TensorOptions());
  load_golden_weights(*vae, "vae");
  auto in = golden_tensors("vae", "inputs");
  auto ref = golden_tensors("vae", "outputs");

  torch::Tensor h = vae->encoder->forward(in["image"]);
  EXPECT_CLOSE_TO_GOLDEN(h, ref["encoder_out"], kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(vae->quant_conv->forward(h), ref["moments"], kForwardTolerance);
  LatentDistribution dist = vae->encode(in["image"]);
  EXPECT_CLOSE_TO_GOLDEN(dist.mean, ref["latent_mean"], kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(dist.logvar, ref["latent_logvar"], kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(dist.std(), ref["latent_std"], kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(dist.mode() * config.scaling_factor, ref["latent_mode_scaled"], kForwardTolerance);
  EXPECT_CLOSE_TO_GOLDEN(vae->decode(in["latent"]), ref["decoded"], kForwardTolerance);
}

class VaeTiledDecode : public ::testing::Test {
 protected:
  void SetUp() override {
    config = AutoencoderKLConfig::from_json(golden_config("vae"), "vae/config.json");
    vae = AutoencoderKL(config, torch::TensorOptions());
    load_golden_weights(*vae, "vae");
    latent = golden_tensors("vae", "inputs")["latent"];  // [2, 4, 16, 16]
    plain = vae->decode(latent);
  }
  torch::NoGradGuard no_grad;
  AutoencoderKLConfig config;
  AutoencoderKL vae{nullptr};
  torch::Tensor latent, plain;
};

TEST_F(VaeTiledDecode, OneTileIsThePlainDecode) {
  // diffusers' default tile for this config: sample_size 32 / scale factor 2 = the whole 16x16 latent.
  EXPECT_EQ(config.sample_size, 32);
  EXPECT_EQ(vae->default_tiling().tile_latent, 16);
  EXPECT_TRUE(torch::equal(vae->decode_tiled(latent, vae->default_tiling()), plain));
  EXPECT_TRUE(torch::equal(vae->decode_tiled(latent, VaeTiling{40, 0.25}), plain));
}

TEST_F(VaeTiledDecode, SmallTilesStayCloseToThePlainDecode) {
  // Each tile normalises (GroupNorm) and attends (mid block) over itself only, so tiles differ from the
  // whole-image decode; the blend keeps the difference small. Values of `plain` reach about 2.5.
  for (const VaeTiling tiling : {VaeTiling{8, 0.25}, VaeTiling{10, 0.5}, VaeTiling{12, 0.25}}) {
    SCOPED_TRACE("tile " + std::to_string(tiling.tile_latent) + " overlap " + std::to_string(tiling.overlap));
    torch::Tensor tiled = vae->decode_tiled(latent, tiling);
    ASSERT_EQ(tiled.sizes(), plain.sizes());
    const double max_err = (tiled - plain).abs().max().item<double>();
    const double mean_err = (tiled - plain).abs().mean().item<double>();
    std::printf("  tile %ld overlap %.2f: max abs diff %.3g, mean %.3g\n", long(tiling.tile_latent), tiling.overlap,
                max_err, mean_err);
    EXPECT_LE(max_err, kTiledMaxError);
    EXPECT_LE(mean_err, kTiledMeanError);
  }
  // The bound still tells a right result from a wrong one: the plain decode shifted by two pixels
  // (what a misplaced tile would give) is further off than any tiling above.
  const double shifted_err = (plain.roll(2, 3) - plain).abs().mean().item<double>();
  std::printf("  plain decode shifted by 2 px: mean abs diff %.3g\n", shifted_err);
  EXPECT_GT(shifted_err, kTiledMeanError);
}

TEST(VaeTiles, LocalDecoderIsReassembledExactly) {
  // A decoder whose output pixel depends only on the latent pixel under it gives the same values in
  // every tile that covers a pixel, so any correctly aligned cross-fade must reproduce the whole decode.
  torch::manual_seed(3);
  const torch::Tensor latent = torch::randn({2, 3, 23, 17});
  for (const int64_t scale : {1, 4}) {
    const auto upsample = [scale](const torch::Tensor& t) {
      return t.repeat_interleave(scale, 2).repeat_interleave(scale, 3) * 2.0 + 1.0;
    };
    const torch::Tensor whole = upsample(latent);
    for (const VaeTiling tiling : {VaeTiling{8, 0.25}, VaeTiling{5, 0.3}, VaeTiling{6, 0.5}, VaeTiling{4, 0.0},
                                   VaeTiling{20, 0.25}}) {
      SCOPED_TRACE("scale " + std::to_string(scale) + " tile " + std::to_string(tiling.tile_latent));
      torch::Tensor tiled = decode_in_tiles(latent, tiling, scale, upsample);
      ASSERT_EQ(tiled.sizes(), whole.sizes());
      EXPECT_LE((tiled - whole).abs().max().item<double>(), 1e-6);
    }
  }
}

TEST(VaeTiles, BlendRampsLinearlyAcrossTheOverlap) {
  // Tiles that decode to their own index: tile 8, overlap 0.25 -> stride 6, band 2 latent pixels = 4
  // image pixels at scale 2. Columns [0, 12) come from tile 0 alone, then tile 1 fades in over 4 columns.
  int calls = 0;
  const auto constant_tile = [&calls](const torch::Tensor& t) {
    return torch::full({t.size(0), 1, 2 * t.size(2), 2 * t.size(3)}, double(calls++));
  };
  torch::Tensor row = decode_in_tiles(torch::zeros({1, 4, 3, 14}), VaeTiling{8, 0.25}, 2, constant_tile)[0][0][0];
  ASSERT_EQ(calls, 3);  // tiles start at latent columns 0, 6, 12
  ASSERT_EQ(row.size(0), 28);
  // The last tile is only 2 latent columns wide, all of them overlap: it never reaches full weight.
  const std::vector<float> expected{0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.25, 0.5, 0.75,  // tile 0, fade to 1
                                    1, 1, 1, 1, 1, 1, 1, 1, 1, 1.25, 1.5, 1.75};             // tile 1, fade to 2
  for (int64_t i = 0; i < 28; ++i) EXPECT_FLOAT_EQ(row[i].item<float>(), expected[i]) << "column " << i;
}

TEST(VaeTiles, RejectsBadSettings) {
  const auto identity = [](const torch::Tensor& t) { return t; };
  EXPECT_THROW(decode_in_tiles(torch::zeros({1, 4, 8, 8}), VaeTiling{0, 0.25}, 1, identity), u3d::Error);
  EXPECT_THROW(decode_in_tiles(torch::zeros({1, 4, 8, 8}), VaeTiling{4, 0.75}, 1, identity), u3d::Error);
  EXPECT_THROW(decode_in_tiles(torch::zeros({4, 8, 8}), VaeTiling{4, 0.25}, 1, identity), u3d::Error);
}

TEST(Vae, ConvertsLegacyAttentionKeys) {
  TensorMap sd{{"decoder.mid_block.attentions.0.query.weight", torch::zeros({2, 2})},
               {"decoder.mid_block.attentions.0.proj_attn.bias", torch::zeros({2})},
               {"encoder.mid_block.attentions.0.key.bias", torch::zeros({2})},
               {"encoder.mid_block.attentions.0.group_norm.weight", torch::zeros({2})},
               {"encoder.down_blocks.0.resnets.0.conv1.weight", torch::zeros({1})}};
  convert_legacy_vae_attention_keys(sd);
  EXPECT_TRUE(sd.count("decoder.mid_block.attentions.0.to_q.weight"));
  EXPECT_TRUE(sd.count("decoder.mid_block.attentions.0.to_out.0.bias"));
  EXPECT_TRUE(sd.count("encoder.mid_block.attentions.0.to_k.bias"));
  EXPECT_TRUE(sd.count("encoder.mid_block.attentions.0.group_norm.weight"));
  EXPECT_TRUE(sd.count("encoder.down_blocks.0.resnets.0.conv1.weight"));
  EXPECT_EQ(sd.size(), 5u);
}

TEST(Vae, RejectsBadShapes) {
  auto config = AutoencoderKLConfig::from_json(golden_config("vae"), "vae/config.json");
  AutoencoderKL vae(config, torch::TensorOptions());
  EXPECT_THROW(vae->encode(torch::zeros({1, 3, 31, 32})), u3d::Error);
  EXPECT_THROW(vae->decode(torch::zeros({1, 3, 8, 8})), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
