// The full-size networks, built from the real configs, have exactly the parameter names and shapes of
// the Python libraries (manifests recorded from diffusers / transformers). Built on the meta device:
// nothing is allocated.
#include <gtest/gtest.h>

#include <map>
#include <vector>

#include "golden.h"
#include "nn/layers/multiview_attention.h"
#include "nn/models/clip_text.h"
#include "nn/models/clip_vision.h"
#include "nn/models/controlnet.h"
#include "nn/models/ip_adapter.h"
#include "nn/models/unet.h"
#include "nn/models/unet_reference.h"
#include "nn/models/vae.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;
using Shapes = std::map<std::string, std::vector<int64_t>>;

nlohmann::json manifest(const std::string& name) { return golden_config("manifests", name + ".json"); }

Shapes manifest_shapes(const nlohmann::json& m) {
  Shapes out;
  for (const auto& [key, shape] : m.at("tensors").items()) out[key] = shape.get<std::vector<int64_t>>();
  return out;
}

Shapes module_shapes(torch::nn::Module& module) {
  Shapes out;
  for (const auto& p : module.named_parameters(true)) out[p.key()] = p.value().sizes().vec();
  return out;
}

void expect_same_shapes(const Shapes& actual, const Shapes& expected) {
  for (const auto& [key, shape] : expected) {
    auto it = actual.find(key);
    if (it == actual.end()) {
      ADD_FAILURE() << "missing parameter " << key;
      continue;
    }
    EXPECT_EQ(it->second, shape) << key;
  }
  for (const auto& [key, shape] : actual) EXPECT_TRUE(expected.count(key)) << "unexpected parameter " << key;
}

const torch::TensorOptions kMeta = torch::TensorOptions().device(torch::kMeta);

TEST(Manifests, UNetSdImageVariations) {
  auto m = manifest("unet_sd_image_variations_plain");
  UNet2DConditionModel unet(UNetConfig::from_json(m.at("constructor_config"), "manifest"), kMeta);
  Shapes shapes = module_shapes(*unet);
  EXPECT_EQ(shapes.size(), m.at("num_tensors").get<size_t>());
  expect_same_shapes(shapes, manifest_shapes(m));
}

// The official ckpt/img2mvimg/unet_state_dict.pth: the plain UNet with an 8-channel conv_in and a class
// embedding; the multi-view processors add no parameters.
TEST(Manifests, UNetUnique3DImg2MvImg) {
  auto m = manifest("unet_unique3d_img2mvimg");
  UNet2DConditionModel unet(UNetConfig::from_json(m.at("constructor_config"), "manifest"), kMeta);
  set_attention_processors(*unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(4)));
  Shapes shapes = module_shapes(*unet);
  EXPECT_EQ(shapes.size(), m.at("num_tensors").get<size_t>());
  expect_same_shapes(shapes, manifest_shapes(m));
}

// The official ckpt/image2normal/unet_state_dict.pth layout: the main UNet, its crosspond_attention
// projections on every attn1, and the reference UNet under "ref_unet.".
TEST(Manifests, UNetUnique3DImage2Normal) {
  auto m = manifest("unet_unique3d_image2normal");
  ReferenceUNet model(UNetConfig::from_json(m.at("constructor_config"), "manifest"), kMeta);
  Shapes shapes = module_shapes(*model.unet);
  EXPECT_EQ(shapes.size(), m.at("num_tensors").get<size_t>());
  expect_same_shapes(shapes, manifest_shapes(m));
}

TEST(Manifests, VaeSd1x) {
  auto m = manifest("vae_sd1x");
  AutoencoderKL vae(AutoencoderKLConfig::from_json(m.at("constructor_config"), "manifest"), kMeta);
  Shapes expected = manifest_shapes(m);
  expect_same_shapes(module_shapes(*vae), expected);

  // A checkpoint with the legacy attention names loads after conversion.
  TensorMap legacy;
  for (const auto& [key, shape] : expected) {
    std::string name = m.at("legacy_key_names").contains(key) ? m.at("legacy_key_names").at(key).get<std::string>() : key;
    legacy[name] = torch::empty(shape, kMeta);
  }
  EXPECT_EQ(legacy.count("decoder.mid_block.attentions.0.query.weight"), 1u);
  convert_legacy_vae_attention_keys(legacy);
  Shapes converted;
  for (const auto& [key, t] : legacy) converted[key] = t.sizes().vec();
  expect_same_shapes(converted, expected);
}

TEST(Manifests, ClipVisionVitL14WithProjection) {
  auto m = manifest("clip_vision_vit_l14_with_projection");
  ClipVisionModelWithProjection clip(ClipVisionConfig::from_json(m.at("constructor_config"), "manifest"), kMeta);
  expect_same_shapes(module_shapes(*clip), manifest_shapes(m));

  TensorMap old_checkpoint{{"vision_model.embeddings.position_ids", torch::empty({1, 257}, kMeta.dtype(torch::kLong))}};
  drop_clip_vision_position_ids(old_checkpoint);
  EXPECT_TRUE(old_checkpoint.empty());
}

// SD 1.5's text_encoder (CLIP ViT-L/14 text tower).
TEST(Manifests, ClipTextVitL14Sd15) {
  auto m = manifest("clip_text_vit_l14_sd15");
  ClipTextModel clip(ClipTextConfig::from_json(m.at("constructor_config"), "manifest"), kMeta);
  EXPECT_EQ(clip->config.eos_token_id, 2);
  Shapes shapes = module_shapes(*clip);
  EXPECT_EQ(shapes.size(), m.at("num_tensors").get<size_t>());
  expect_same_shapes(shapes, manifest_shapes(m));
}

TEST(Manifests, ControlNetSd15) {
  auto m = manifest("controlnet_sd15");
  ControlNetModel controlnet(ControlNetConfig::from_json(m.at("constructor_config"), "manifest"), kMeta);
  Shapes shapes = module_shapes(*controlnet);
  EXPECT_EQ(shapes.size(), m.at("num_tensors").get<size_t>());
  expect_same_shapes(shapes, manifest_shapes(m));
}

// ip-adapter_sd15 on the SD 1.5 UNet (the sd-image-variations UNet has the same architecture): the
// adapter has the original file's names and shapes, and the UNet the diffusers names after loading.
TEST(Manifests, IpAdapterSd15) {
  auto m = manifest("ip_adapter_sd15");
  UNet2DConditionModel unet(
      UNetConfig::from_json(manifest("unet_sd_image_variations_plain").at("constructor_config"), "manifest"), kMeta);
  const auto& c = m.at("constructor_config");
  IpAdapter adapter(*unet, c.at("image_embed_dim").get<int64_t>(), c.at("num_tokens").get<int64_t>(), 1.0, kMeta);
  expect_same_shapes(module_shapes(*adapter), manifest_shapes(m));

  Shapes unet_shapes = module_shapes(*unet);
  int processor_keys = 0;
  for (const auto& [key, shape] : m.at("diffusers_keys_after_load_ip_adapter").items()) {
    if (key.starts_with("encoder_hid_proj.")) continue;  // the projection lives in IpAdapter
    ASSERT_TRUE(unet_shapes.count(key)) << key;
    EXPECT_EQ(unet_shapes[key], shape.get<std::vector<int64_t>>()) << key;
    ++processor_keys;
  }
  EXPECT_EQ(processor_keys, 32);
}

}  // namespace
}  // namespace u3d::nn
