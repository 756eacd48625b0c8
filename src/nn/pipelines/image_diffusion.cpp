#include "nn/pipelines/image_diffusion.h"

#include <string>

#include "core/error.h"
#include "core/memory.h"
#include "core/progress.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/layers/layers.h"
#include "nn/pipelines/guidance.h"
#include "nn/schedulers/scheduler_config.h"
#include "nn/preprocess/pil_resize.h"

namespace u3d::nn {

namespace {

void check_rgb(const torch::Tensor& image) {
  if (image.dim() != 3 || image.size(2) != 3 || image.scalar_type() != torch::kUInt8 || image.size(0) == 0 ||
      image.size(1) == 0)
    throw Error("image diffusion: condition images must be uint8 RGB [H, W, 3], got " + c10::str(image.sizes()) + " " +
                c10::toString(image.scalar_type()));
}

void check_sizes(const ImageDiffusionModels& models, const ImageDiffusionSettings& s) {
  const int64_t factor = models.vae->config.scale_factor();
  for (int64_t side : {s.width, s.height, s.condition_width, s.condition_height})
    if (side <= 0 || side % factor != 0)
      throw Error("image diffusion: image sizes must be positive multiples of " + std::to_string(factor) + ", got " +
                  std::to_string(side));
  if (s.images_per_condition < 1 || s.steps < 1)
    throw Error("image diffusion: images_per_condition and steps must be at least 1");
}

}  // namespace

torch::Tensor vae_preprocess(const torch::Tensor& rgb, int64_t width, int64_t height) {
  torch::Tensor resized = pil_resize(rgb, width, height, PilFilter::Lanczos);
  return (resized.to(torch::kFloat) / 255.0f * 2.0f - 1.0f).permute({2, 0, 1}).unsqueeze(0);
}

std::vector<std::filesystem::path> conditioning_model_files(const DiffusersFolder& folder) {
  return {folder.component_config("image_encoder"), folder.component_weights("image_encoder"),
          folder.component_config("vae"),           folder.component_weights("vae"),
          folder.preprocessor_config(),             folder.scheduler_config()};
}

ConditioningModels load_conditioning_models(const DiffusersFolder& folder, Precision precision,
                                            const CheckpointReader& reader) {
  check_precision_supported(precision, torch::kCPU);
  const auto clip_config = folder.component_config("image_encoder");
  const auto clip_weights = folder.component_weights("image_encoder");
  const auto vae_config = folder.component_config("vae");
  const auto vae_weights = folder.component_weights("vae");
  const auto processor_config = folder.preprocessor_config();
  const auto scheduler_config = folder.scheduler_config();

  ConditioningModels m;
  m.feature_extractor = std::make_unique<ClipImageProcessor>(
      ClipImageProcessorConfig::from_json(read_json_file(processor_config), processor_config.string()));
  m.scheduler = make_scheduler(parse_scheduler_config(read_json_file(scheduler_config), scheduler_config.string()),
                               SchedulerKind::EulerAncestral);
  m.image_encoder = ClipVisionModelWithProjection(
      ClipVisionConfig::from_json(read_json_file(clip_config), clip_config.string()), reader.options());
  allocate_in_precision(*m.image_encoder, precision);
  reader.load(*m.image_encoder, clip_weights, clip_policy());
  m.vae = AutoencoderKL(AutoencoderKLConfig::from_json(read_json_file(vae_config), vae_config.string()),
                        reader.options());
  allocate_in_precision(*m.vae, precision);
  reader.load(*m.vae, vae_weights);
  pack_weights_in_place(*m.vae);
  return m;
}

ImageConditions encode_image_conditions(const ImageDiffusionModels& models,
                                        const std::vector<torch::Tensor>& condition_images,
                                        const ImageDiffusionSettings& s, TensorMap* trace) {
  torch::NoGradGuard no_grad;
  auto record = [trace](const std::string& name, const torch::Tensor& value) {
    if (trace) (*trace)[name] = value;
  };
  if (condition_images.empty()) throw Error("image diffusion: no condition image");
  if (models.image_encoder.is_empty())
    throw Error("image diffusion: this model's networks were freed by an earlier run (free_networks_as_done)");
  for (const auto& image : condition_images) check_rgb(image);
  check_sizes(models, s);
  const bool guidance = s.guidance_scale > 1.0;

  // 1. Image embeddings, each repeated for its outputs.
  std::vector<torch::Tensor> pixels;
  for (const auto& image : condition_images) pixels.push_back(models.feature_extractor.pixel_values(image));
  const torch::Tensor pixel_values = torch::cat(pixels);
  record("clip_pixel_values", pixel_values);
  ImageConditions out;
  out.embeddings = models.image_encoder->forward(pixel_values)
                       .image_embeds.unsqueeze(1)
                       .repeat_interleave(s.images_per_condition, 0);
  if (guidance) out.embeddings = torch::cat({torch::zeros_like(out.embeddings), out.embeddings});
  record("image_embeddings", out.embeddings);

  // 2. Condition latents.
  // One image at a time: the VAE works on each image alone (its GroupNorms are per sample), and its
  // activations at 512 px are about 1 GB per image in fp32.
  std::vector<torch::Tensor> encoded;
  for (const auto& image : condition_images)
    encoded.push_back(models.vae->encode(vae_preprocess(image, s.condition_width, s.condition_height)).mode());
  out.latents = torch::cat(encoded) * models.vae->config.scaling_factor;
  record("cond_latents", out.latents);
  if (s.free_networks_as_done) {  // the encoder, and what the encoding left in the heap
    models.image_encoder = nullptr;
    release_freed_memory();
  }
  if (guidance) out.latents = torch::cat({torch::zeros_like(out.latents), out.latents});
  return out;
}

torch::Tensor sample_image_diffusion(const ImageDiffusionModels& models, const ImageConditions& conditions,
                                     const ImageDiffusionSettings& s, NoiseSource& noise, TensorMap* trace) {
  torch::NoGradGuard no_grad;
  auto record = [trace](const std::string& name, const torch::Tensor& value) {
    if (trace) (*trace)[name] = value;
  };
  check_sizes(models, s);
  const bool guidance = s.guidance_scale > 1.0;
  const torch::Tensor& embeddings = conditions.embeddings;
  const torch::Tensor& condition = conditions.latents;
  const int64_t factor = models.vae->config.scale_factor();
  if (!embeddings.defined() || !condition.defined() || embeddings.dim() != 3 || condition.dim() != 4 ||
      embeddings.size(0) % (guidance ? 2 : 1) != 0 || condition.size(0) == 0 ||
      embeddings.size(0) % condition.size(0) != 0 || condition.size(2) != s.condition_height / factor ||
      condition.size(3) != s.condition_width / factor)
    throw Error(
        "image diffusion: the conditions do not fit the settings (encode_image_conditions with the same "
        "settings)");
  const int64_t batch = embeddings.size(0) / (guidance ? 2 : 1);

  // 3. The sampling loop.
  Scheduler& scheduler = models.scheduler;
  scheduler.set_timesteps(s.steps);
  record("timesteps", scheduler.timesteps());
  const std::vector<int64_t> latent_shape{batch, models.vae->config.latent_channels, s.height / factor, s.width / factor};
  torch::Tensor latents = s.initial_latents.defined() ? s.initial_latents : noise.randn(latent_shape);
  if (latents.sizes() != at::IntArrayRef(latent_shape))
    throw Error("image diffusion: initial latents must be " + c10::str(at::IntArrayRef(latent_shape)) + ", got " +
                c10::str(latents.sizes()));
  latents = latents * scheduler.init_noise_sigma();
  for (int i = 0; i < scheduler.num_steps(); ++i) {
    const std::string step = "step" + std::to_string(i);
    const torch::Tensor input = scheduler.scale_model_input(latents, i);
    const torch::Tensor t = scheduler.timestep(i);
    torch::Tensor prediction, raw;
    if (guidance) {
      GuidedPrediction guided = guided_prediction(
          s.guidance_scale,
          [&](GuidanceHalf half) {
            return models.denoiser(input, t, batch_half(embeddings, half), batch_half(condition, half));
          },
          trace != nullptr);
      prediction = guided.combined;
      raw = guided.raw;
    } else {
      prediction = raw = models.denoiser(input, t, embeddings, condition);
    }
    if (trace) {  // as the official doubled batch
      record(step + ".unet.latent_model_input", guidance ? torch::cat({input, input}) : input);
      record(step + ".unet.timestep", t);
      record(step + ".unet.encoder_hidden_states", embeddings);
      record(step + ".unet.condition_latents", condition);
      record(step + ".unet.noise_pred_raw", raw);
    }
    SchedulerStep next = scheduler.step(prediction, i, latents, noise);
    if (trace) {
      record(step + ".scheduler.model_output", prediction);
      record(step + ".scheduler.sample", latents);
      record(step + ".scheduler.prev_sample", next.prev_sample);
      record(step + ".scheduler.pred_original_sample", next.pred_original_sample);
    }
    latents = next.prev_sample;
    progress_step("denoise", i + 1, scheduler.num_steps());
  }

  if (s.free_networks_as_done) {
    if (models.free_denoiser) models.free_denoiser();
    release_freed_memory();
  }

  // 4. Decode, one image at a time as the encoding.
  std::vector<torch::Tensor> decoded;
  for (const torch::Tensor& latent : (latents / models.vae->config.scaling_factor).split(1))
    decoded.push_back((models.vae->decode(latent) / 2 + 0.5).clamp(0, 1).permute({0, 2, 3, 1}));
  torch::Tensor images = torch::cat(decoded).contiguous();
  record("images", images);
  return images;
}

torch::Tensor run_image_diffusion(const ImageDiffusionModels& models,
                                  const std::vector<torch::Tensor>& condition_images, const ImageDiffusionSettings& s,
                                  NoiseSource& noise, TensorMap* trace) {
  const ImageConditions conditions = encode_image_conditions(models, condition_images, s, trace);
  return sample_image_diffusion(models, conditions, s, noise, trace);
}

}  // namespace u3d::nn
