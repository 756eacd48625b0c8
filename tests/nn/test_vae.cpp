#include "nn/vae.h"

#include <gtest/gtest.h>

#include "golden.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

TEST(Vae, MatchesDiffusersEncodeDecode) {
  torch::NoGradGuard no_grad;
  auto config = AutoencoderKLConfig::from_json(golden_config("vae"), "vae/config.json");
  AutoencoderKL vae(config, torch::TensorOptions());
  load_weights_strict(*vae, golden_tensors("vae", "weights"));
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
