#include "nn/models/ip_adapter.h"

#include <gtest/gtest.h>

#include "golden.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

struct IpAdapterUNet {
  explicit IpAdapterUNet(double scale)
      : unet(UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json"), torch::TensorOptions()) {
    load_golden_weights(*unet, "unet_base");
    adapter = load_ip_adapter(*unet, golden_dir("ip_adapter") / "weights.safetensors", scale);
  }
  UNet2DConditionModel unet;
  IpAdapter adapter{nullptr};
};

TEST(IpAdapter, ProjectionAndUNetMatchDiffusers) {
  torch::NoGradGuard no_grad;
  const double scale = golden_config("ip_adapter").at("ip_scale").get<double>();
  IpAdapterUNet m(scale);
  EXPECT_EQ(m.adapter->processors.size(), 4u);
  auto in = golden_tensors("ip_adapter", "inputs");
  auto ref = golden_tensors("ip_adapter", "outputs");
  const torch::Tensor image_embeds = in["image_embeds"].squeeze(1);  // one image per prompt

  EXPECT_CLOSE_TO_GOLDEN(m.adapter->image_proj->forward(image_embeds), ref["image_proj_tokens"].squeeze(1),
                         kForwardTolerance);
  const torch::Tensor context = m.adapter->context(in["encoder_hidden_states"], image_embeds);
  EXPECT_EQ(context.size(1), 3 + 4);
  EXPECT_CLOSE_TO_GOLDEN(m.unet->forward(in["sample"], in["timestep"], context), ref["sample_out"], kForwardTolerance);
}

// The original file's ip_adapter.<i> entries land on the attn2 processors diffusers names them by.
TEST(IpAdapter, OriginalKeysMapToDiffusersNames) {
  IpAdapterUNet m(1.0);
  auto diffusers = golden_tensors("ip_adapter", "unet_ip_keys_diffusers");
  auto unet_params = m.unet->named_parameters(true);
  const std::string projection = "encoder_hid_proj.image_projection_layers.0.";
  int checked = 0;
  for (const auto& [key, value] : diffusers) {
    torch::Tensor ours;
    if (key.starts_with(projection)) {
      std::string rest = key.substr(projection.size());
      if (rest.starts_with("image_embeds.")) rest = "proj." + rest.substr(13);
      ours = m.adapter->image_proj->named_parameters(true)[rest];
    } else {
      ASSERT_TRUE(unet_params.contains(key)) << key;
      ours = unet_params[key];
    }
    EXPECT_TRUE(torch::equal(ours, value)) << key;
    ++checked;
  }
  EXPECT_EQ(checked, 12);
}

TEST(IpAdapter, ScaleZeroIsThePlainUNet) {
  torch::NoGradGuard no_grad;
  IpAdapterUNet m(0.0);
  auto in = golden_tensors("ip_adapter", "inputs");
  const torch::Tensor context = m.adapter->context(in["encoder_hidden_states"], in["image_embeds"].squeeze(1));
  const torch::Tensor with_adapter = m.unet->forward(in["sample"], in["timestep"], context);
  UNet2DConditionModel plain(UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json"),
                             torch::TensorOptions());
  load_golden_weights(*plain, "unet_base");
  EXPECT_LE(max_abs_diff(with_adapter, plain->forward(in["sample"], in["timestep"], in["encoder_hidden_states"])), 1e-6);
}

TEST(IpAdapter, RejectsFileWithoutImageProjection) {
  UNet2DConditionModel unet(UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json"),
                            torch::TensorOptions());
  EXPECT_THROW(load_ip_adapter(*unet, golden_dir("ip_adapter") / "unet_ip_keys_diffusers.safetensors", 1.0), u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
