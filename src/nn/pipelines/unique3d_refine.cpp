#include "nn/pipelines/unique3d_refine.h"

#include <algorithm>
#include <utility>

#include "core/error.h"
#include "core/memory.h"
#include "core/progress.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/layers/layers.h"
#include "nn/pipelines/image_diffusion.h"
#include "nn/preprocess/pil_resize.h"
#include "nn/schedulers/scheduler_config.h"
#include "nn/schedulers/scheduler_sigma_base.h"

namespace u3d::nn {

namespace {

constexpr int64_t kViews = 4;

void check_rgb(const torch::Tensor& image, const std::string& what) {
  if (image.dim() != 3 || image.size(2) != 3 || image.scalar_type() != torch::kUInt8 || image.size(0) == 0 ||
      image.size(1) == 0)
    throw Error("refine: " + what + " must be uint8 RGB [H, W, 3], got " + c10::str(image.sizes()) + " " +
                c10::toString(image.scalar_type()));
}

void check_views(const std::vector<torch::Tensor>& views) {
  if (views.size() != size_t(kViews)) throw Error("refine: needs 4 views, got " + std::to_string(views.size()));
  for (const auto& v : views) {
    check_rgb(v, "each view");
    if (v.sizes() != views[0].sizes()) throw Error("refine: the four views must have one size");
  }
}

// app/utils.make_image_grid with rows=2: views 0 1 on top, 2 3 below.
torch::Tensor make_grid(const std::vector<torch::Tensor>& views) {
  return torch::cat({torch::cat({views[0], views[1]}, 1), torch::cat({views[2], views[3]}, 1)}, 0);
}

// Every file the stage reads, each checked to exist (an Error names the first missing one).
struct RefineFiles {
  explicit RefineFiles(const RefineCheckpoints& c) {
    const DiffusersFolder base(c.base, "the Stable Diffusion 1.5 base model is runwayml/stable-diffusion-v1-5 "
                                       "(diffusers layout) on Hugging Face");
    const DiffusersFolder ckpt(c.ckpt, "the tile ControlNet is ckpt/controlnet-tile of the Unique3D checkpoints "
                                       "(Hugging Face space Wuvin/Unique3D)");
    const DiffusersFolder ip(c.ip_adapter, "the IP-Adapter is the Hugging Face repository h94/IP-Adapter");
    unet_config = base.component_config("unet");
    unet_weights = base.component_weights("unet");
    vae_config = base.component_config("vae");
    vae_weights = base.component_weights("vae");
    text_config = base.component_config("text_encoder");
    text_weights = base.component_weights("text_encoder");
    merges = base.file("tokenizer/merges.txt");
    processor_config = base.preprocessor_config();
    scheduler_config = base.scheduler_config();
    controlnet_config = ckpt.component_config("controlnet-tile");
    controlnet_weights = ckpt.component_weights("controlnet-tile");
    image_encoder_config = ip.component_config("models/image_encoder");
    image_encoder_weights = ip.component_weights("models/image_encoder");
    adapter_weights = ip.file("models/ip-adapter_sd15.safetensors");
  }
  std::vector<std::filesystem::path> all() const {
    return {unet_config,       unet_weights,       vae_config,           vae_weights,           text_config,
            text_weights,      merges,             processor_config,     scheduler_config,      controlnet_config,
            controlnet_weights, image_encoder_config, image_encoder_weights, adapter_weights};
  }
  std::filesystem::path unet_config, unet_weights, vae_config, vae_weights, text_config, text_weights, merges,
      processor_config, scheduler_config, controlnet_config, controlnet_weights, image_encoder_config,
      image_encoder_weights, adapter_weights;
};

}  // namespace

std::vector<std::filesystem::path> RefineModel::files(const RefineCheckpoints& checkpoints) {
  return RefineFiles(checkpoints).all();
}

std::unique_ptr<RefineEncoders> RefineEncoders::load(const RefineCheckpoints& c, Precision precision,
                                                     const CheckpointReader& reader) {
  check_precision_supported(precision, torch::kCPU);
  const RefineFiles f(c);  // every file is checked before any weights are read
  auto m = std::make_unique<RefineEncoders>();
  const torch::TensorOptions cpu = reader.options();
  m->tokenizer = std::make_unique<ClipTokenizer>(ClipTokenizer::load(f.merges));
  m->feature_extractor = std::make_unique<ClipImageProcessor>(
      ClipImageProcessorConfig::from_json(read_json_file(f.processor_config), f.processor_config.string()));
  m->text_encoder = ClipTextModel(ClipTextConfig::from_json(read_json_file(f.text_config), f.text_config.string()), cpu);
  allocate_in_precision(*m->text_encoder, precision);
  reader.load(*m->text_encoder, f.text_weights, clip_policy());
  m->image_encoder = ClipVisionModelWithProjection(
      ClipVisionConfig::from_json(read_json_file(f.image_encoder_config), f.image_encoder_config.string()), cpu);
  allocate_in_precision(*m->image_encoder, precision);
  reader.load(*m->image_encoder, f.image_encoder_weights, clip_policy());
  m->vae = AutoencoderKL(AutoencoderKLConfig::from_json(read_json_file(f.vae_config), f.vae_config.string()), cpu);
  allocate_in_precision(*m->vae, precision);
  reader.load(*m->vae, f.vae_weights);
  pack_weights_in_place(*m->vae);
  return m;
}

RefineConditioning RefineEncoders::encode(const std::vector<torch::Tensor>& views, const torch::Tensor& front,
                                          const RefineSettings& s, TensorMap* trace) {
  torch::NoGradGuard no_grad;
  auto record = [trace](const std::string& name, const torch::Tensor& value) {
    if (trace) (*trace)[name] = value;
  };
  if (text_encoder.is_empty() || vae.is_empty())
    throw Error("refine: these encoders were freed by an earlier run (free_networks_as_done)");
  check_views(views);
  check_rgb(front, "the front image");
  const int64_t factor = vae->config.scale_factor() * 2;  // the grid splits into halves of whole latents
  if (s.size <= 0 || s.size % factor != 0)
    throw Error("refine: the size must be a positive multiple of " + std::to_string(factor) + ", got " +
                std::to_string(s.size));
  const bool guidance = s.guidance_scale > 1.0;
  // Text embeddings [negative, prompt] and the front image's CLIP embedding [zeros, embedding].
  std::vector<std::string> prompts{s.prompt};
  if (guidance) prompts.insert(prompts.begin(), s.negative_prompt);
  RefineConditioning out;
  out.prompt_embeds = text_encoder->forward(tokenizer->input_ids(prompts)).last_hidden_state;
  out.image_embeds = image_encoder->forward(feature_extractor->pixel_values(front)).image_embeds;
  if (guidance) out.image_embeds = torch::cat({torch::zeros_like(out.image_embeds), out.image_embeds});
  record("prompt_embeds", out.prompt_embeds);
  record("image_embeds", out.image_embeds);
  if (s.free_networks_as_done) {
    text_encoder = nullptr;
    image_encoder = nullptr;
    release_freed_memory();
  }

  // Images: the grid, its bicubic resize as the control image (PIL's default filter, [0, 1]), and the
  // VaeImageProcessor input (Lanczos, [-1, 1]) that the VAE encodes.
  const torch::Tensor grid = make_grid(views);
  record("grid", grid);
  out.control = pil_resize(grid, s.size, s.size, PilFilter::Bicubic);
  out.control = (out.control.to(torch::kFloat) / 255.0f).permute({2, 0, 1}).unsqueeze(0);
  record("control_image", out.control);
  const torch::Tensor init_image = vae_preprocess(grid, s.size, s.size);
  record("init_image", init_image);
  out.grid = vae->encode(init_image);
  if (s.free_networks_as_done) {
    vae = nullptr;
    release_freed_memory();
  }
  return out;
}

std::unique_ptr<RefineModel> RefineModel::load(const RefineCheckpoints& c, Precision precision,
                                               const CheckpointReader& reader) {
  check_precision_supported(precision, torch::kCPU);
  const RefineFiles f(c);  // every file is checked before any weights are read
  auto m = std::make_unique<RefineModel>();
  const torch::TensorOptions cpu = reader.options();
  m->scheduler = make_scheduler(parse_scheduler_config(read_json_file(f.scheduler_config), f.scheduler_config.string()),
                                SchedulerKind::EulerAncestral);
  m->unet = UNet2DConditionModel(UNetConfig::from_json(read_json_file(f.unet_config), f.unet_config.string()), cpu);
  allocate_in_precision(*m->unet, precision);
  reader.load(*m->unet, f.unet_weights);
  pack_weights_in_place(*m->unet);
  m->ip_adapter = load_ip_adapter(*m->unet, f.adapter_weights, 1.0, reader);
  set_precision(*m->ip_adapter, precision);  // built to the file's sizes as it is read
  m->controlnet = ControlNetModel(
      ControlNetConfig::from_json(read_json_file(f.controlnet_config), f.controlnet_config.string()), cpu);
  allocate_in_precision(*m->controlnet, precision);
  reader.load(*m->controlnet, f.controlnet_weights);
  pack_weights_in_place(*m->controlnet);
  m->vae = AutoencoderKL(AutoencoderKLConfig::from_json(read_json_file(f.vae_config), f.vae_config.string()), cpu);
  allocate_in_precision(*m->vae, precision);
  reader.load(*m->vae, f.vae_weights);
  return m;
}

torch::Tensor RefineModel::run(const RefineConditioning& conditioning, const RefineSettings& s, NoiseSource& noise,
                               TensorMap* trace) {
  torch::NoGradGuard no_grad;
  auto record = [trace](const std::string& name, const torch::Tensor& value) {
    if (trace) (*trace)[name] = value;
  };
  if (unet.is_empty())
    throw Error("refine: this model's networks were freed by an earlier run (free_networks_as_done)");
  if (s.steps < 1 || !(s.strength > 0.0 && s.strength <= 1.0))
    throw Error("refine: steps must be at least 1 and strength in (0, 1]");
  const int run_steps = std::min(static_cast<int>(s.steps * s.strength), s.steps);
  if (run_steps < 1)
    throw Error("refine: steps x strength must be at least 1 (" + std::to_string(s.steps) + " x " +
                std::to_string(s.strength) + ")");
  const bool guidance = s.guidance_scale > 1.0;
  const int64_t batch = guidance ? 2 : 1;
  const torch::Tensor& prompt_embeds = conditioning.prompt_embeds;
  const int64_t latent_side = s.size / vae->config.scale_factor();
  if (!prompt_embeds.defined() || !conditioning.image_embeds.defined() || prompt_embeds.dim() != 3 ||
      prompt_embeds.size(0) != batch || conditioning.image_embeds.size(0) != batch ||
      !conditioning.control.defined() || conditioning.control.dim() != 4 || conditioning.control.size(2) != s.size ||
      !conditioning.grid.mean.defined() || conditioning.grid.mean.dim() != 4 ||
      conditioning.grid.mean.size(2) != latent_side)
    throw Error("refine: the conditioning does not fit the settings (RefineEncoders::encode with the same settings)");
  ip_adapter->set_scale(s.ip_adapter_scale);

  const torch::Tensor unet_context = ip_adapter->context(prompt_embeds, conditioning.image_embeds);
  // The control image is the same at every step: its embedding (both guidance halves, as the doubled
  // batch) is computed once, where diffusers' ControlNet recomputes it every step.
  const torch::Tensor control = controlnet->embed_condition(
      guidance ? torch::cat({conditioning.control, conditioning.control}) : conditioning.control);

  // img2img start (diffusers' get_timesteps): the schedule for all steps, entered at step `start`.
  auto* sigma_scheduler = dynamic_cast<SigmaScheduler*>(scheduler.get());
  TORCH_CHECK(sigma_scheduler, "refine: the scheduler must be an Euler sampler");
  scheduler->set_timesteps(s.steps);
  const int start = s.steps - run_steps;
  record("timesteps", scheduler->timesteps().narrow(0, start, run_steps));
  const LatentDistribution& posterior = conditioning.grid;
  const torch::Tensor init_latents =
      (posterior.mean + posterior.std() * noise.randn(posterior.mean.sizes())) * vae->config.scaling_factor;
  record("init_latents", init_latents);
  torch::Tensor latents = sigma_scheduler->add_noise(init_latents, noise.randn(init_latents.sizes()), start);

  for (int i = start; i < s.steps; ++i) {
    record("latents." + std::to_string(i - start), latents);
    const torch::Tensor input = scheduler->scale_model_input(guidance ? torch::cat({latents, latents}) : latents, i);
    const torch::Tensor t = scheduler->timestep(i);
    ControlNetOutput residuals = controlnet->forward_embedded(input, t, prompt_embeds, control, s.conditioning_scale);
    UNetExtras extras;
    extras.down_block_additional_residuals = std::move(residuals.down_block_res_samples);
    extras.mid_block_additional_residual = std::move(residuals.mid_block_res_sample);
    torch::Tensor prediction = unet->forward(input, t, unet_context, std::move(extras));
    if (guidance) {
      auto halves = prediction.chunk(2);
      prediction = halves[0] + s.guidance_scale * (halves[1] - halves[0]);
    }
    record("noise_pred." + std::to_string(i - start), prediction);
    latents = scheduler->step(prediction, i, latents, noise).prev_sample;
    progress_step("denoise", i - start + 1, run_steps);
  }
  record("latents." + std::to_string(run_steps), latents);

  if (s.free_networks_as_done) {
    unet = nullptr;
    ip_adapter = nullptr;
    controlnet = nullptr;
    release_freed_memory();
  }
  torch::Tensor image = vae->decode(latents / vae->config.scaling_factor);
  image = (image / 2 + 0.5).clamp(0, 1).permute({0, 2, 3, 1})[0];  // [size, size, 3]
  record("images", image);
  // app/utils.split_image with rows=2: the quarters in grid order.
  const int64_t half = s.size / 2;
  std::vector<torch::Tensor> quarters;
  for (int64_t row = 0; row < 2; ++row)
    for (int64_t col = 0; col < 2; ++col) quarters.push_back(image.narrow(0, row * half, half).narrow(1, col * half, half));
  return torch::stack(quarters).contiguous();
}

}  // namespace u3d::nn
