#pragma once
// Unique3D's refinement of the four views (the official refine_rgb in scripts/multiview_inference.py,
// through refine_lr_with_sd in scripts/refine_lr_to_sr.py): the four views pasted into a 2x2 grid are
// redrawn at 1024 px by diffusers' StableDiffusionControlNetImg2ImgPipeline on Stable Diffusion 1.5 with
// the tile ControlNet (control image: the grid resized to 1024 px) and IP-Adapter conditioning on the
// front image, then cut back into four views of 512 px.
//
// The official call, as it runs (diffusers 0.27):
//  - prompt "4views, multiview"; the negative prompt is EMPTY: refine_lr_with_sd passes its NEG_PROMPT as
//    `neg_prompt=`, which the pipeline swallows in **kwargs, so the unconditional half encodes "";
//  - strength 0.2 of 50 EulerAncestral steps (scheduler built from the base model's scheduler config):
//    the schedule for 50 steps, of which the last int(50 * 0.2) = 10 run (get_timesteps);
//  - init latents: VAE encode of the grid (Lanczos-resized to 1024, [-1, 1]), a SAMPLE of the latent
//    distribution (mean + std * noise) times 0.18215, then noised to the first step's sigma;
//  - guidance 5.0 on both halves [negative, prompt]; the ControlNet (conditioning scale 1.0) sees the text
//    embeddings only, the UNet the text embeddings followed by the 4 IP-Adapter tokens (scale 1.0) of
//    the front image's CLIP ViT-H/14 embedding (the negative half: the tokens of a zero embedding);
//  - VAE decode, (x / 2 + 0.5) clamped to [0, 1].
// Noise is drawn in diffusers' order: the VAE sample, the img2img noise, then one draw per step.
//
// Checkpoints (RefineCheckpoints): the Stable Diffusion 1.5 base in the diffusers layout
// (runwayml/stable-diffusion-v1-5: unet, vae, text_encoder, tokenizer/merges.txt, scheduler,
// feature_extractor, whose CLIPImageProcessor prepares the IP-Adapter image); Unique3D's
// ckpt/controlnet-tile (config.json + diffusion_pytorch_model.*); the h94/IP-Adapter repository
// (models/ip-adapter_sd15.safetensors and the ViT-H/14 encoder models/image_encoder).
#include <torch/torch.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nn/checkpoint/checkpoint_reader.h"
#include "nn/checkpoint/tensor_map.h"
#include "nn/models/clip_text.h"
#include "nn/models/clip_vision.h"
#include "nn/models/controlnet.h"
#include "nn/models/ip_adapter.h"
#include "nn/models/unet.h"
#include "nn/models/vae.h"
#include "nn/precision.h"
#include "nn/preprocess/clip_image_processor.h"
#include "nn/preprocess/clip_tokenizer.h"
#include "nn/schedulers/noise_source.h"
#include "nn/schedulers/scheduler.h"

namespace u3d::nn {

struct RefineCheckpoints {
  std::filesystem::path base;        // runwayml/stable-diffusion-v1-5, diffusers layout
  std::filesystem::path ckpt;        // Unique3D's ckpt/ folder: uses ckpt/controlnet-tile
  std::filesystem::path ip_adapter;  // h94/IP-Adapter: uses models/ip-adapter_sd15.safetensors, models/image_encoder
};

struct RefineSettings {
  int64_t size = 1024;  // side of the grid the pass runs at; each view comes back at size / 2
  int steps = 50;       // of which the last int(steps * strength) run
  double strength = 0.2;
  double guidance_scale = 5.0;
  double conditioning_scale = 1.0;  // ControlNet
  double ip_adapter_scale = 1.0;
  std::string prompt = "4views, multiview";
  std::string negative_prompt;  // empty, as the official call ends up (see above)
  // Free each network as soon as this run no longer needs it (docs/networks.md, "Memory"): the model
  // cannot run again afterwards. The pipeline stages run each model once and set it. RefineEncoders
  // frees its CLIP encoders before encoding the grid and its VAE after; RefineModel frees the UNet,
  // IP-Adapter and ControlNet before decoding.
  bool free_networks_as_done = false;
};

// What the encoding half makes of the prompt, the front image and the four views: everything the
// denoising half needs besides its networks.
struct RefineConditioning {
  torch::Tensor prompt_embeds;  // [2, 77, D]: [negative, prompt] with guidance, else [1, 77, D]
  torch::Tensor image_embeds;   // [2, E]: [zeros, front image] with guidance, else [1, E]
  torch::Tensor control;        // [1, 3, size, size] in [0, 1]: the grid resized with PIL's default (bicubic)
  LatentDistribution grid;      // the VAE posterior of the grid (VaeImageProcessor: Lanczos, [-1, 1])
};

// The refinement comes in two halves, loaded one after the other so that their weights never share
// memory: the encoders (CLIP text encoder, the IP-Adapter's ViT-H/14 image encoder and the VAE, about
// 3.3 GB in fp32) run once and are freed before the denoising half (UNet with IP-Adapter, ControlNet and
// the VAE again for decoding, about 5.3 GB) loads. Encoding the 1024 px grid takes about 3 GB of
// activations in fp32; in the encoding half, with its CLIP encoders freed first, they meet no other weights. Each load() checks that every file of both halves is there (an Error names the first
// missing one and where it comes from) before reading any weights, then loads and converts to
// `precision`; with a checking `reader` the model is built on the meta device, only to check the checkpoints.
class RefineEncoders {
 public:
  static std::unique_ptr<RefineEncoders> load(const RefineCheckpoints& checkpoints, Precision precision,
                                              const CheckpointReader& reader = {});
  // views: the four views, uint8 RGB [H, W, 3] of one size, in the multi-view model's order (pasted as
  // the grid [0 1; 2 3]); front: uint8 RGB [H, W, 3], the front image on white (the official app passes
  // the input image, upscaled, alpha composited on white). `trace`, when given, receives grid,
  // control_image, init_image, prompt_embeds and image_embeds.
  RefineConditioning encode(const std::vector<torch::Tensor>& views, const torch::Tensor& front,
                            const RefineSettings& settings, TensorMap* trace = nullptr);

  std::unique_ptr<ClipTokenizer> tokenizer;
  ClipTextModel text_encoder{nullptr};
  std::unique_ptr<ClipImageProcessor> feature_extractor;
  ClipVisionModelWithProjection image_encoder{nullptr};
  AutoencoderKL vae{nullptr};
};

class RefineModel {
 public:
  static std::unique_ptr<RefineModel> load(const RefineCheckpoints& checkpoints, Precision precision,
                                           const CheckpointReader& reader = {});
  // The files the two halves read, checked to exist (an Error names the first missing one); reads nothing.
  static std::vector<std::filesystem::path> files(const RefineCheckpoints& checkpoints);

  // conditioning: RefineEncoders::encode with the same settings. Returns the four refined views, float
  // [4, size / 2, size / 2, 3] in [0, 1]. Reports progress_step("denoise", i, n) per step. `trace`, when
  // given, receives timesteps, init_latents, latents.<i> (before step i of the run; latents.<n> after the
  // last), noise_pred.<i> (step i's guided prediction) and images.
  torch::Tensor run(const RefineConditioning& conditioning, const RefineSettings& settings, NoiseSource& noise,
                    TensorMap* trace = nullptr);

  UNet2DConditionModel unet{nullptr};
  IpAdapter ip_adapter{nullptr};
  ControlNetModel controlnet{nullptr};
  AutoencoderKL vae{nullptr};
  std::unique_ptr<Scheduler> scheduler;  // EulerAncestral
};

}  // namespace u3d::nn
