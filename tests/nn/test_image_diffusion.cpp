// The sampling loop of Unique3D's image-conditioned pipelines against the official pipelines' 2-step
// traces with injected noise: the multi-view model (golden unet_mv: four views of one image, guidance
// 1.5) and the normal model (golden unet_ref: two condition images, guidance 2.0). The official traces
// run the guidance halves as one doubled batch; ours runs them one after the other (guidance.h).
#include "nn/pipelines/image_diffusion.h"

#include <gtest/gtest.h>

#include "golden.h"
#include "nn/layers/multiview_attention.h"
#include "nn/pipelines/guidance.h"
#include "nn/models/unet.h"
#include "nn/models/unet_reference.h"
#include "nn/schedulers/scheduler_config.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

// The golden README's pipeline bounds: latents (up to ~70) 1e-3, everything else 1e-4.
constexpr double kLatentTolerance = 1e-3;

// The tiny CLIP, feature extractor (32 px), VAE and the SD scheduler as EulerAncestral, as the cases use.
struct SharedModels {
  SharedModels()
      : clip(ClipVisionConfig::from_json(golden_config("clip_vision"), "clip_vision/config.json"), torch::TensorOptions()),
        processor(ClipImageProcessorConfig::from_json(golden_config("clip_vision", "preprocessor_config_tiny32.json"),
                                                      "preprocessor_config_tiny32.json")),
        vae(AutoencoderKLConfig::from_json(golden_config("vae"), "vae/config.json"), torch::TensorOptions()),
        scheduler(make_scheduler(parse_scheduler_config(golden_config("scheduler", "sd_scheduler_config.json"), "sd"),
                                 SchedulerKind::EulerAncestral)) {
    load_golden_weights(*clip, "clip_vision", clip_policy());
    load_golden_weights(*vae, "vae");
  }
  ClipVisionModelWithProjection clip;
  ClipImageProcessor processor;
  AutoencoderKL vae;
  std::unique_ptr<Scheduler> scheduler;
};

void expect_trace(TensorMap& trace, TensorMap& ref, int steps) {
  ASSERT_FALSE(trace.empty());
  for (const char* name : {"image_embeddings", "cond_latents", "timesteps", "images"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(trace.count(name));
    EXPECT_CLOSE_TO_GOLDEN(trace[name], ref[std::string("pipe.") + name], 1e-4);
  }
  for (int i = 0; i < steps; ++i) {
    const std::string step = "step" + std::to_string(i);
    for (const char* part : {".unet.latent_model_input", ".unet.timestep", ".unet.encoder_hidden_states",
                             ".unet.condition_latents", ".unet.noise_pred_raw", ".scheduler.model_output",
                             ".scheduler.sample", ".scheduler.prev_sample", ".scheduler.pred_original_sample"}) {
      const std::string name = step + part;
      SCOPED_TRACE(name);
      ASSERT_TRUE(trace.count(name));
      const bool latent = name.find("sample") != std::string::npos || name.find("latent_model_input") != std::string::npos;
      EXPECT_CLOSE_TO_GOLDEN(trace[name], ref["pipe." + name], latent ? kLatentTolerance : 1e-4);
    }
  }
}

TEST(ImageDiffusion, MultiViewPipelineMatchesTheOfficialTrace) {
  torch::NoGradGuard no_grad;
  SharedModels shared;
  UNet2DConditionModel unet(UNetConfig::from_json(golden_config("unet_mv"), "unet_mv/config.json"), torch::TensorOptions());
  load_golden_weights(*unet, "unet_mv");
  set_attention_processors(*unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(4)));
  const torch::Tensor labels = torch::arange(4, torch::kLong);

  ImageDiffusionModels models{shared.clip, shared.processor, shared.vae, *shared.scheduler,
                              [&](const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& embeddings,
                                  const torch::Tensor& condition) {
                                UNetExtras extras;
                                extras.class_labels = labels.repeat(x.size(0) / 4);
                                extras.condition_latents = condition;
                                return unet->forward(x, t, embeddings, extras);
                              }, nullptr};
  auto in = golden_tensors("unet_mv", "inputs");
  auto ref = golden_tensors("unet_mv", "outputs");
  ImageDiffusionSettings settings;
  settings.width = settings.height = settings.condition_width = settings.condition_height = 32;
  settings.images_per_condition = 4;
  settings.steps = 2;
  settings.guidance_scale = 1.5;
  settings.initial_latents = in["pipe.init_noise"];
  GoldenPipelineNoise noise(in, /*draws_initial_latents=*/false);
  TensorMap trace;
  torch::Tensor images = run_image_diffusion(models, {in["pipe.test_image_uint8"]}, settings, noise, &trace);
  EXPECT_EQ(noise.draws, 2);
  EXPECT_EQ(images.sizes(), (std::vector<int64_t>{4, 32, 32, 3}));
  EXPECT_CLOSE_TO_GOLDEN(trace["clip_pixel_values"], ref["pipe.clip_pixel_values"], 1e-6);
  expect_trace(trace, ref, 2);
}

TEST(ImageDiffusion, NormalPipelineWithReferenceUNetMatchesTheOfficialTrace) {
  torch::NoGradGuard no_grad;
  SharedModels shared;
  ReferenceUNet model(UNetConfig::from_json(golden_config("unet_ref"), "unet_ref/config.json"), torch::TensorOptions());
  load_golden_weights(*model.unet, "unet_ref", LoadPolicy{{"ref_unet.*"}, {}});
  load_golden_weights(*model.reference, "unet_base");

  ImageDiffusionModels models{shared.clip, shared.processor, shared.vae, *shared.scheduler,
                              [&](const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& embeddings,
                                  const torch::Tensor& condition) { return model.forward(x, t, embeddings, condition); }, nullptr};
  auto in = golden_tensors("unet_ref", "inputs");
  auto ref = golden_tensors("unet_ref", "outputs");
  const torch::Tensor image = golden_tensors("unet_mv", "inputs")["pipe.test_image_uint8"];
  ImageDiffusionSettings settings;
  settings.width = settings.height = settings.condition_width = settings.condition_height = 32;
  settings.steps = 2;
  settings.guidance_scale = 2.0;
  settings.initial_latents = in["pipe.init_noise"];
  GoldenPipelineNoise noise(in, /*draws_initial_latents=*/false);
  TensorMap trace;
  // The case's two condition images: the test image and its horizontal mirror.
  run_image_diffusion(models, {image, image.flip(1).contiguous()}, settings, noise, &trace);
  expect_trace(trace, ref, 2);
}

TEST(ImageDiffusion, SeededRunsRepeatAndBadInputsAreRejected) {
  torch::NoGradGuard no_grad;
  SharedModels shared;
  UNet2DConditionModel unet(UNetConfig::from_json(golden_config("unet_base"), "unet_base/config.json"),
                            torch::TensorOptions());
  load_golden_weights(*unet, "unet_base");
  ImageDiffusionModels models{shared.clip, shared.processor, shared.vae, *shared.scheduler,
                              [&](const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& e,
                                  const torch::Tensor&) { return unet->forward(x, t, e); }, nullptr};
  const torch::Tensor image = golden_tensors("unet_mv", "inputs")["pipe.test_image_uint8"];
  ImageDiffusionSettings settings;
  settings.width = settings.height = settings.condition_width = settings.condition_height = 32;
  settings.steps = 2;
  SeededNoise a(7), b(7), c(8);
  torch::Tensor first = run_image_diffusion(models, {image}, settings, a);
  EXPECT_TRUE(torch::equal(first, run_image_diffusion(models, {image}, settings, b)));
  EXPECT_FALSE(torch::equal(first, run_image_diffusion(models, {image}, settings, c)));

  SeededNoise noise(1);
  EXPECT_THROW(run_image_diffusion(models, {}, settings, noise), u3d::Error);
  EXPECT_THROW(run_image_diffusion(models, {image.to(torch::kFloat)}, settings, noise), u3d::Error);
  ImageDiffusionSettings odd = settings;
  odd.width = 30;
  EXPECT_THROW(run_image_diffusion(models, {image}, odd, noise), u3d::Error);
  ImageDiffusionSettings wrong = settings;
  wrong.initial_latents = torch::zeros({2, 4, 4, 4});
  EXPECT_THROW(run_image_diffusion(models, {image}, wrong, noise), u3d::Error);
  // Conditions encoded at another size (or none) do not fit the sampling settings.
  ImageDiffusionSettings larger = settings;
  larger.condition_width = larger.condition_height = 64;
  const ImageConditions conditions = encode_image_conditions(models, {image}, larger);
  EXPECT_THROW(sample_image_diffusion(models, conditions, settings, noise), u3d::Error);
  EXPECT_THROW(sample_image_diffusion(models, ImageConditions{}, settings, noise), u3d::Error);
}

TEST(Guidance, RunsTheUnconditionalHalfFirstAndCombinesAsTheDoubledBatch) {
  const torch::Tensor doubled = torch::arange(12, torch::kFloat).reshape({4, 3});
  std::vector<GuidanceHalf> order;
  GuidedPrediction guided = guided_prediction(
      3.0,
      [&](GuidanceHalf half) {
        order.push_back(half);
        return batch_half(doubled, half) * 2;
      },
      /*keep_raw=*/true);
  EXPECT_EQ(order, (std::vector<GuidanceHalf>{GuidanceHalf::kUnconditional, GuidanceHalf::kConditional}));
  const auto halves = (doubled * 2).chunk(2);
  EXPECT_TRUE(torch::allclose(guided.combined, halves[0] + 3.0 * (halves[1] - halves[0])));
  EXPECT_TRUE(torch::equal(guided.raw, doubled * 2));
  EXPECT_FALSE(guided_prediction(3.0, [&](GuidanceHalf half) { return batch_half(doubled, half); }).raw.defined());
  EXPECT_TRUE(torch::equal(batch_half(doubled, GuidanceHalf::kConditional), doubled.narrow(0, 2, 2)));
  EXPECT_THROW(batch_half(torch::zeros({3, 2}), GuidanceHalf::kUnconditional), u3d::Error);
  EXPECT_THROW(guided_prediction(2.0, [](GuidanceHalf half) {
                 return torch::zeros({half == GuidanceHalf::kConditional ? 2 : 1});
               }),
               u3d::Error);
}

}  // namespace
}  // namespace u3d::nn
