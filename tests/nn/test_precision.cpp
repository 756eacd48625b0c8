// Reduced precision (nn/precision.h): the conversion rules, and every golden network run in bf16
// against its fp32 Python reference (issue target: relative error at most 2e-2).
#include "nn/precision.h"

#include <gtest/gtest.h>

#include "golden.h"
#include "nn/layers/attention.h"
#include "nn/layers/multiview_attention.h"
#include "nn/models/clip_text.h"
#include "nn/models/clip_vision.h"
#include "nn/models/controlnet.h"
#include "nn/models/ip_adapter.h"
#include "nn/models/unet.h"
#include "nn/models/vae.h"
#include "required_skip.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

constexpr double kBf16Tolerance = 2e-2;

TEST(Precision, ParsesNamesAndRejectsOthers) {
  EXPECT_EQ(parse_precision("fp32", "--dtype"), Precision::kFp32);
  EXPECT_EQ(parse_precision("bf16", "--dtype"), Precision::kBf16);
  EXPECT_EQ(parse_precision("fp16", "--dtype"), Precision::kFp16);
  for (Precision p : {Precision::kFp32, Precision::kBf16, Precision::kFp16})
    EXPECT_EQ(parse_precision(precision_name(p), "x"), p);
  try {
    parse_precision("float32", "--dtype");
    FAIL() << "no error";
  } catch (const u3d::Error& e) {
    EXPECT_NE(std::string(e.what()).find("--dtype"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("bf16"), std::string::npos);
  }
}

TEST(Precision, Fp16NeedsCudaAndTheCpuDefaultFollowsTheInstructionSet) {
  EXPECT_THROW(check_precision_supported(Precision::kFp16, torch::kCPU), u3d::Error);
  EXPECT_NO_THROW(check_precision_supported(Precision::kBf16, torch::kCPU));
  EXPECT_NO_THROW(check_precision_supported(Precision::kFp32, torch::kCPU));
  EXPECT_EQ(default_precision(torch::kCPU), cpu_has_bf16_kernels() ? Precision::kBf16 : Precision::kFp32);
  EXPECT_EQ(default_precision(torch::Device(torch::kCUDA, 0)), Precision::kFp16);
}

TEST(Precision, NormsKeepFp32WeightsAndEverythingElseConverts) {
  torch::NoGradGuard no_grad;
  auto config = UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json");
  UNet2DConditionModel unet(config, torch::TensorOptions());
  set_precision(*unet, Precision::kBf16);
  size_t norms = 0, others = 0;
  for (const auto& p : unet->named_parameters()) {
    const bool norm = p.key().find("norm") != std::string::npos;
    EXPECT_EQ(p.value().scalar_type(), norm ? torch::kFloat : torch::kBFloat16) << p.key();
    (norm ? norms : others)++;
  }
  EXPECT_GT(norms, 0u);
  EXPECT_GT(others, 0u);
  // The members that forward() uses see the converted tensors.
  EXPECT_EQ(unet->conv_in->weight.scalar_type(), torch::kBFloat16);
  EXPECT_EQ(unet->conv_norm_out->weight.scalar_type(), torch::kFloat);
}

// Loading into a model given its bf16 types first converts the file once, straight into bf16: the same
// bits as loading into fp32 and converting after (fp16 and fp32 files alike), with the parameters in one
// block and buffers keeping their values.
TEST(Precision, AllocatingInPrecisionLoadsWhatSetPrecisionGives) {
  torch::NoGradGuard no_grad;
  auto config = UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json");
  const TensorMap fp32 = golden_tensors("unet_base", "weights");
  TensorMap fp16;
  for (const auto& [name, t] : fp32) fp16[name] = t.to(torch::kHalf);
  for (const TensorMap* file : std::initializer_list<const TensorMap*>{&fp32, &fp16}) {
    UNet2DConditionModel after(config, torch::TensorOptions());
    load_state_dict(*after, *file, {}, "file");
    set_precision(*after, Precision::kBf16);
    UNet2DConditionModel before(config, torch::TensorOptions());
    allocate_in_precision(*before, Precision::kBf16);
    load_state_dict(*before, *file, {}, "file");
    const auto expected = after->named_parameters();
    const void* block = nullptr;
    for (const auto& p : before->named_parameters()) {
      const torch::Tensor& want = expected[p.key()];
      EXPECT_EQ(p.value().scalar_type(), want.scalar_type()) << p.key();
      EXPECT_TRUE(torch::equal(p.value(), want)) << p.key();
      EXPECT_EQ(reinterpret_cast<uintptr_t>(p.value().data_ptr()) % 64, 0u) << p.key();
      if (!block) block = p.value().storage().data();
      EXPECT_EQ(p.value().storage().data(), block) << p.key() << " is not in the one block";
    }
    for (const auto& b : before->named_buffers()) EXPECT_TRUE(torch::equal(b.value(), after->named_buffers()[b.key()]));
  }
}

TEST(Precision, NormsComputeInFp32ForBf16Activations) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(3);
  GroupNorm group_norm(4, 16, 1e-5, torch::TensorOptions());
  LayerNorm layer_norm(16, 1e-5, torch::TensorOptions());
  for (auto* m : {static_cast<torch::nn::Module*>(group_norm.get()), static_cast<torch::nn::Module*>(layer_norm.get())})
    randomize_parameters(*m, 1.0);
  // A large common offset: variance computed in bf16 would lose it entirely.
  torch::Tensor x = (torch::randn({2, 16, 8, 8}) + 300.0).to(torch::kBFloat16);
  torch::Tensor gn = group_norm->forward(x);
  EXPECT_EQ(gn.scalar_type(), torch::kBFloat16);
  torch::Tensor gn_ref = torch::group_norm(x.to(torch::kFloat), 4, group_norm->weight, group_norm->bias, 1e-5);
  EXPECT_TRUE(torch::equal(gn, gn_ref.to(torch::kBFloat16)));
  torch::Tensor tokens = x.flatten(2).transpose(1, 2);
  torch::Tensor ln = layer_norm->forward(tokens);
  EXPECT_EQ(ln.scalar_type(), torch::kBFloat16);
  torch::Tensor ln_ref = torch::layer_norm(tokens.to(torch::kFloat), {16}, layer_norm->weight, layer_norm->bias, 1e-5);
  EXPECT_TRUE(torch::equal(ln, ln_ref.to(torch::kBFloat16)));
}

// The attention kernel relies on ATen's bf16 softmax computing in fp32 and rounding once.
TEST(Precision, Bf16SoftmaxIsTheFp32SoftmaxRoundedOnce) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::manual_seed(4);
  torch::Tensor scores = (torch::randn({3, 37, 4096}) * 4.0).to(torch::kBFloat16);
  torch::Tensor expected = scores.to(torch::kFloat).softmax(-1).to(torch::kBFloat16);
  EXPECT_TRUE(torch::equal(scores.softmax(-1), expected));
  // And so the attention result in bf16 stays close to the fp32 one.
  torch::Tensor q = torch::randn({2, 300, 64}), k = torch::randn({2, 300, 64}), v = torch::randn({2, 300, 64});
  torch::Tensor ref = multi_head_attention(q, k, v, 4, 0.25);
  torch::Tensor low = multi_head_attention(q.to(torch::kBFloat16), k.to(torch::kBFloat16), v.to(torch::kBFloat16), 4, 0.25);
  EXPECT_EQ(low.scalar_type(), torch::kBFloat16);
  EXPECT_LT(relative_error(low, ref), 1e-2);
}

TEST(PrecisionGolden, UNetBaseInBf16) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  auto config = UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json");
  UNet2DConditionModel unet(config, torch::TensorOptions());
  load_golden_weights(*unet, "unet_base");
  set_precision(*unet, Precision::kBf16);
  auto in = golden_tensors("unet_base", "inputs");
  auto ref = golden_tensors("unet_base", "outputs");
  for (const char* c : {"a", "b"}) {
    SCOPED_TRACE(c);
    const std::string p = c;
    torch::Tensor out = unet->forward(in[p + ".sample"], in[p + ".timestep"], in[p + ".encoder_hidden_states"]);
    EXPECT_EQ(out.scalar_type(), torch::kFloat);
    EXPECT_RELATIVE_TO_GOLDEN(out, ref[p + ".sample_out"], kBf16Tolerance);
  }
}

TEST(PrecisionGolden, MultiViewUNetInBf16) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  auto config = UNetConfig::from_json(golden_config("unet_mv"), "unet_mv/config.json");
  UNet2DConditionModel unet(config, torch::TensorOptions());
  load_golden_weights(*unet, "unet_mv");
  set_precision(*unet, Precision::kBf16);
  set_attention_processors(*unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(4)));
  auto in = golden_tensors("unet_mv", "inputs");
  auto ref = golden_tensors("unet_mv", "outputs");
  UNetExtras extras;
  extras.class_labels = in["class_labels"];
  extras.condition_latents = in["condition_latents"];
  torch::Tensor out = unet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"], extras);
  EXPECT_EQ(out.scalar_type(), torch::kFloat);
  EXPECT_RELATIVE_TO_GOLDEN(out, ref["sample_out"], kBf16Tolerance);
}

TEST(PrecisionGolden, VaeInBf16) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  auto config = AutoencoderKLConfig::from_json(golden_config("vae"), "vae/config.json");
  AutoencoderKL vae(config, torch::TensorOptions());
  load_golden_weights(*vae, "vae");
  set_precision(*vae, Precision::kBf16);
  auto in = golden_tensors("vae", "inputs");
  auto ref = golden_tensors("vae", "outputs");
  LatentDistribution dist = vae->encode(in["image"]);
  EXPECT_EQ(dist.mean.scalar_type(), torch::kFloat);
  EXPECT_RELATIVE_TO_GOLDEN(dist.mean, ref["latent_mean"], kBf16Tolerance);
  EXPECT_RELATIVE_TO_GOLDEN(dist.logvar, ref["latent_logvar"], kBf16Tolerance);
  torch::Tensor decoded = vae->decode(in["latent"]);
  EXPECT_EQ(decoded.scalar_type(), torch::kFloat);
  EXPECT_RELATIVE_TO_GOLDEN(decoded, ref["decoded"], kBf16Tolerance);
}

TEST(PrecisionGolden, ClipVisionInBf16) {
  torch::NoGradGuard no_grad;
  auto config = ClipVisionConfig::from_json(golden_config("clip_vision"), "clip_vision/config.json");
  ClipVisionModelWithProjection model(config, torch::TensorOptions());
  load_golden_weights(*model, "clip_vision", clip_policy());
  set_precision(*model, Precision::kBf16);
  auto in = golden_tensors("clip_vision", "inputs");
  auto ref = golden_tensors("clip_vision", "outputs");
  ClipVisionOutput out = model->forward(in["pixel_values"], true);
  EXPECT_EQ(out.image_embeds.scalar_type(), torch::kFloat);
  EXPECT_RELATIVE_TO_GOLDEN(out.image_embeds, ref["image_embeds"], kBf16Tolerance);
  EXPECT_RELATIVE_TO_GOLDEN(out.last_hidden_state, ref["last_hidden_state"], kBf16Tolerance);
  for (size_t i = 0; i < out.hidden_states.size(); ++i)
    EXPECT_RELATIVE_TO_GOLDEN(out.hidden_states[i], ref["hidden_states." + std::to_string(i)], kBf16Tolerance);
}

TEST(PrecisionGolden, ClipTextInBf16) {
  torch::NoGradGuard no_grad;
  ClipTextModel model(ClipTextConfig::from_json(golden_config("clip_text"), "clip_text/config.json"),
                      torch::TensorOptions());
  load_golden_weights(*model, "clip_text", clip_policy());
  set_precision(*model, Precision::kBf16);
  auto in = golden_tensors("clip_text", "inputs");
  auto ref = golden_tensors("clip_text", "outputs");
  ClipTextOutput out = model->forward(in["input_ids"]);
  EXPECT_EQ(out.last_hidden_state.scalar_type(), torch::kFloat);
  EXPECT_RELATIVE_TO_GOLDEN(out.last_hidden_state, ref["last_hidden_state"], kBf16Tolerance);
  EXPECT_RELATIVE_TO_GOLDEN(out.pooler_output, ref["pooler_output"], kBf16Tolerance);
}

TEST(PrecisionGolden, ControlNetAndIpAdapterInBf16) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  ControlNetModel controlnet(ControlNetConfig::from_json(golden_config("controlnet"), "controlnet/config.json"),
                             torch::TensorOptions());
  load_golden_weights(*controlnet, "controlnet");
  set_precision(*controlnet, Precision::kBf16);
  auto in = golden_tensors("controlnet", "inputs");
  auto ref = golden_tensors("controlnet", "outputs");
  ControlNetOutput out = controlnet->forward(in["sample"], in["timestep"], in["encoder_hidden_states"],
                                             in["controlnet_cond"], in["conditioning_scale"].item<double>());
  EXPECT_EQ(out.mid_block_res_sample.scalar_type(), torch::kFloat);
  for (size_t i = 0; i < out.down_block_res_samples.size(); ++i)
    EXPECT_RELATIVE_TO_GOLDEN(out.down_block_res_samples[i], ref["down_block_res_samples." + std::to_string(i)],
                              kBf16Tolerance);
  EXPECT_RELATIVE_TO_GOLDEN(out.mid_block_res_sample, ref["mid_block_res_sample"], kBf16Tolerance);

  UNet2DConditionModel unet(UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json"),
                            torch::TensorOptions());
  load_golden_weights(*unet, "unet_base");
  IpAdapter adapter = load_ip_adapter(*unet, golden_dir("ip_adapter") / "weights.safetensors",
                                      golden_config("ip_adapter").at("ip_scale").get<double>());
  set_precision(*unet, Precision::kBf16);
  set_precision(*adapter, Precision::kBf16);
  EXPECT_EQ(adapter->processors[0]->to_k_ip->weight.scalar_type(), torch::kBFloat16);
  auto ip_in = golden_tensors("ip_adapter", "inputs");
  const torch::Tensor context = adapter->context(ip_in["encoder_hidden_states"], ip_in["image_embeds"].squeeze(1));
  EXPECT_EQ(context.scalar_type(), torch::kFloat);
  EXPECT_RELATIVE_TO_GOLDEN(unet->forward(ip_in["sample"], ip_in["timestep"], context),
                            golden_tensors("ip_adapter", "outputs")["sample_out"], kBf16Tolerance);
}

}  // namespace
}  // namespace u3d::nn
