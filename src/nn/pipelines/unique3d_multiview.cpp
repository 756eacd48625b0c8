#include "nn/pipelines/unique3d_multiview.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/pth_reader.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/layers/multiview_attention.h"
#include "nn/schedulers/scheduler_config.h"

namespace u3d::nn {

namespace {

constexpr int64_t kViews = 4;

TensorMap load_weights(const std::filesystem::path& path) {
  return path.extension() == ".safetensors" ? load_safetensors(path) : load_pth(path);
}

}  // namespace

std::unique_ptr<MultiViewModel> MultiViewModel::load(const std::filesystem::path& root, Precision precision) {
  check_precision_supported(precision, torch::kCPU);
  const DiffusersFolder folder(root);
  // Every file first, so that a missing one is reported before minutes of loading.
  const auto unet_config = folder.component_config("unet");
  const auto unet_weights = folder.file("unet_state_dict.pth");
  const auto clip_config = folder.component_config("image_encoder");
  const auto clip_weights = folder.component_weights("image_encoder");
  const auto vae_config = folder.component_config("vae");
  const auto vae_weights = folder.component_weights("vae");
  const auto processor_config = folder.preprocessor_config();
  const auto scheduler_config = folder.scheduler_config();

  auto m = std::make_unique<MultiViewModel>();
  m->feature_extractor = std::make_unique<ClipImageProcessor>(
      ClipImageProcessorConfig::from_json(read_json_file(processor_config), processor_config.string()));
  m->scheduler = make_scheduler(parse_scheduler_config(read_json_file(scheduler_config), scheduler_config.string()),
                                SchedulerKind::EulerAncestral);

  // image2mvimage.yaml: cat_condition (conv_in takes noisy and condition latents) and 8 class labels.
  UNetConfig config = UNetConfig::from_json(read_json_file(unet_config), unet_config.string());
  config.in_channels = 2 * config.out_channels;
  config.num_class_embeds = 8;
  m->unet = UNet2DConditionModel(config, torch::TensorOptions());
  load_state_dict(*m->unet, load_weights(unet_weights), {}, unet_weights.string());
  set_attention_processors(*m->unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(kViews)));

  m->image_encoder = ClipVisionModelWithProjection(
      ClipVisionConfig::from_json(read_json_file(clip_config), clip_config.string()), torch::TensorOptions());
  load_state_dict(*m->image_encoder, load_weights(clip_weights), clip_policy(), clip_weights.string());
  m->vae = AutoencoderKL(AutoencoderKLConfig::from_json(read_json_file(vae_config), vae_config.string()),
                         torch::TensorOptions());
  load_state_dict(*m->vae, load_weights(vae_weights), {}, vae_weights.string());

  for (torch::nn::Module* module : {static_cast<torch::nn::Module*>(m->unet.get()),
                                    static_cast<torch::nn::Module*>(m->image_encoder.get()),
                                    static_cast<torch::nn::Module*>(m->vae.get())})
    set_precision(*module, precision);
  return m;
}

torch::Tensor MultiViewModel::run(const torch::Tensor& condition, const MultiViewSettings& s, NoiseSource& noise,
                                  TensorMap* trace) {
  torch::NoGradGuard no_grad;
  const torch::Tensor labels = torch::arange(kViews, torch::kLong);
  ImageDiffusionModels models{image_encoder, *feature_extractor, vae, *scheduler,
                              [&](const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& embeddings,
                                  const torch::Tensor& condition_latents) {
                                UNetExtras extras;
                                extras.class_labels = labels.repeat(x.size(0) / kViews);
                                extras.condition_latents = condition_latents;
                                return unet->forward(x, t, embeddings, extras);
                              }};
  ImageDiffusionSettings settings;
  settings.width = settings.height = settings.condition_width = settings.condition_height = s.size;
  settings.images_per_condition = kViews;
  settings.steps = s.steps;
  settings.guidance_scale = s.guidance_scale;
  return run_image_diffusion(models, {condition}, settings, noise, trace);
}

}  // namespace u3d::nn
