#pragma once
// The sampling loop of Unique3D's two image-conditioned pipelines, step for step as the official code
// runs it: StableDiffusionImage2MVCustomPipeline (four views from one image) and
// StableDiffusionImageCustomPipeline (a normal map per view), both subclasses of diffusers'
// StableDiffusionImageVariationPipeline:
//  1. CLIP image embeddings of each condition image [B, 1, D], each repeated for its
//     images_per_condition outputs; with guidance, zeros in front for the unconditional half;
//  2. condition latents: VaeImageProcessor (Pillow Lanczos resize, [-1, 1]), VAE encode, mode times
//     the scaling factor; with guidance, zeros in front;
//  3. latents N(0, 1) times init_noise_sigma; per step scaled, run through the denoiser (with guidance
//     once per half, nn/pipelines/guidance.h, where the official code doubles the batch), combined as
//     uncond + g (cond - uncond), and stepped by the scheduler;
//  4. VAE decode of latents / scaling, (x / 2 + 0.5) clamped to [0, 1].
// The denoiser is a function, so the multi-view UNet (class labels, concatenated condition) and the
// reference UNet (reference pass over the condition) plug in unchanged.
#include <torch/torch.h>

#include <functional>
#include <memory>
#include <vector>

#include "nn/checkpoint/checkpoint_reader.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/tensor_map.h"
#include "nn/models/clip_vision.h"
#include "nn/models/vae.h"
#include "nn/precision.h"
#include "nn/preprocess/clip_image_processor.h"
#include "nn/schedulers/noise_source.h"
#include "nn/schedulers/scheduler.h"

namespace u3d::nn {

// (latent input [M, 4, h, w], timestep 0-dim, image embeddings [M, 1, D], condition latents [C, 4, h', w'] with M a
// multiple of C) -> noise prediction [M, 4, h, w].
using Denoiser = std::function<torch::Tensor(const torch::Tensor& latent_input, const torch::Tensor& timestep,
                                             const torch::Tensor& image_embeddings,
                                             const torch::Tensor& condition_latents)>;

// diffusers' VaeImageProcessor.preprocess of one uint8 RGB [H, W, 3] image: Pillow Lanczos resize to
// width x height, [0, 255] -> [-1, 1], as float [1, 3, height, width].
torch::Tensor vae_preprocess(const torch::Tensor& rgb, int64_t width, int64_t height);

// The parts both Unique3D stages take from a diffusers folder of sd-image-variations: the CLIP image
// encoder with its feature extractor, the VAE, and the scheduler config built as EulerAncestral (as the
// official trainers' construct_pipeline does).
struct ConditioningModels {
  ClipVisionModelWithProjection image_encoder{nullptr};
  std::unique_ptr<ClipImageProcessor> feature_extractor;
  AutoencoderKL vae{nullptr};
  std::unique_ptr<Scheduler> scheduler;
};

// Checks that `precision` runs on the CPU and that every file is in `folder` before reading any weights
// (an Error names the problem or the first missing file), then loads (or checks, with `reader`) and
// converts to `precision`.
ConditioningModels load_conditioning_models(const DiffusersFolder& folder, Precision precision,
                                            const CheckpointReader& reader = {});
// The files load_conditioning_models reads, checked to exist; reads nothing.
std::vector<std::filesystem::path> conditioning_model_files(const DiffusersFolder& folder);

struct ImageDiffusionModels {
  ClipVisionModelWithProjection& image_encoder;
  const ClipImageProcessor& feature_extractor;
  AutoencoderKL& vae;
  Scheduler& scheduler;
  Denoiser denoiser;
  std::function<void()> free_denoiser;  // frees the networks behind `denoiser` (free_networks_as_done)
};

struct ImageDiffusionSettings {
  int64_t width = 256, height = 256;                      // output images; multiples of the VAE factor
  int64_t condition_width = 256, condition_height = 256;  // size the condition is encoded at
  int64_t images_per_condition = 1;                       // 4 for the multi-view model
  int steps = 30;
  double guidance_scale = 1.5;  // classifier-free guidance when > 1
  // Optional [B * images_per_condition, 4, height / f, width / f] N(0, 1) latents (before
  // init_noise_sigma, as diffusers' `latents=`); drawn from the noise source when undefined.
  torch::Tensor initial_latents;
  // Free the image encoder once the conditions are encoded and the denoiser (free_denoiser) once the
  // loop is done, before the decoding; `models` cannot run again afterwards.
  bool free_networks_as_done = false;
};

// Steps 1 and 2 of the loop: what the denoiser is conditioned on, for B condition images.
struct ImageConditions {
  torch::Tensor embeddings;  // [B * images_per_condition, 1, D], twice that with guidance
  torch::Tensor latents;     // [B, 4, condition_height / f, condition_width / f], twice that with guidance
};

// condition_images: uint8 RGB [H, W, 3] each. Frees the image encoder (and `models` cannot encode again)
// when settings.free_networks_as_done. `trace` receives clip_pixel_values, image_embeddings and
// cond_latents.
ImageConditions encode_image_conditions(const ImageDiffusionModels& models,
                                        const std::vector<torch::Tensor>& condition_images,
                                        const ImageDiffusionSettings& settings, TensorMap* trace = nullptr);

// Steps 3 and 4. Returns float [B * images_per_condition, height, width, 3] in [0, 1]. Initial latents
// (when not given) and the scheduler's per-step noise come from `noise`, in the order diffusers draws them.
// Reports progress_step("denoise", i, steps). Frees the denoiser before decoding when
// settings.free_networks_as_done. `trace` receives timesteps, step<i>.unet.{latent_model_input, timestep,
// encoder_hidden_states, condition_latents, noise_pred_raw}, step<i>.scheduler.{model_output, sample,
// prev_sample, pred_original_sample} and images.
torch::Tensor sample_image_diffusion(const ImageDiffusionModels& models, const ImageConditions& conditions,
                                     const ImageDiffusionSettings& settings, NoiseSource& noise,
                                     TensorMap* trace = nullptr);

// Both halves in turn; `trace` gets the golden cases' names without "pipe.".
torch::Tensor run_image_diffusion(const ImageDiffusionModels& models, const std::vector<torch::Tensor>& condition_images,
                                  const ImageDiffusionSettings& settings, NoiseSource& noise, TensorMap* trace = nullptr);

}  // namespace u3d::nn
