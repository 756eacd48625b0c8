#include "nn/pipelines/unique3d_multiview.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/layers/layers.h"
#include "nn/layers/multiview_attention.h"

namespace u3d::nn {

namespace {

constexpr int64_t kViews = 4;

}  // namespace

std::vector<std::filesystem::path> MultiViewModel::files(const std::filesystem::path& root) {
  const DiffusersFolder folder(root);
  std::vector<std::filesystem::path> files = {folder.component_config("unet"), folder.file("unet_state_dict.pth")};
  for (auto& f : conditioning_model_files(folder)) files.push_back(std::move(f));
  return files;
}

std::unique_ptr<MultiViewModel> MultiViewModel::load(const std::filesystem::path& root, Precision precision,
                                                     const CheckpointReader& reader) {
  const DiffusersFolder folder(root);
  // The UNet's files are checked before load_conditioning_models reads any weights.
  const auto unet_config = folder.component_config("unet");
  const auto unet_weights = folder.file("unet_state_dict.pth");

  auto m = std::make_unique<MultiViewModel>();
  m->parts = load_conditioning_models(folder, precision, reader);
  // image2mvimage.yaml: cat_condition (conv_in takes noisy and condition latents) and 8 class labels.
  UNetConfig config = UNetConfig::from_json(read_json_file(unet_config), unet_config.string());
  config.in_channels = 2 * config.out_channels;
  config.num_class_embeds = 8;
  m->unet = UNet2DConditionModel(config, reader.options());
  allocate_in_precision(*m->unet, precision);
  reader.load(*m->unet, unet_weights);
  pack_weights_in_place(*m->unet);
  set_attention_processors(*m->unet, self_attention_only(std::make_shared<MultiViewAttentionProcessor>(kViews)));
  return m;
}

torch::Tensor MultiViewModel::run(const torch::Tensor& condition, const MultiViewSettings& s, NoiseSource& noise,
                                  TensorMap* trace) {
  torch::NoGradGuard no_grad;
  const torch::Tensor labels = torch::arange(kViews, torch::kLong);
  ImageDiffusionModels models{parts.image_encoder, *parts.feature_extractor, parts.vae, *parts.scheduler,
                              [&](const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& embeddings,
                                  const torch::Tensor& condition_latents) {
                                UNetExtras extras;
                                extras.class_labels = labels.repeat(x.size(0) / kViews);
                                extras.condition_latents = condition_latents;
                                return unet->forward(x, t, embeddings, extras);
                              },
                              [this] { unet = nullptr; }};
  ImageDiffusionSettings settings;
  settings.width = settings.height = settings.condition_width = settings.condition_height = s.size;
  settings.images_per_condition = kViews;
  settings.steps = s.steps;
  settings.guidance_scale = s.guidance_scale;
  settings.free_networks_as_done = s.free_networks_as_done;
  return run_image_diffusion(models, {condition}, settings, noise, trace);
}

}  // namespace u3d::nn
