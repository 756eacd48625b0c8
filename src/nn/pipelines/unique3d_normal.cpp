#include "nn/pipelines/unique3d_normal.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/state_dict_loader.h"

namespace u3d::nn {

std::vector<std::filesystem::path> NormalModel::files(const std::filesystem::path& image_variations,
                                                     const std::filesystem::path& image2normal) {
  const DiffusersFolder base(image_variations);
  const DiffusersFolder unique3d(image2normal);
  std::vector<std::filesystem::path> files = {base.component_config("unet"), base.component_weights("unet"),
                                              unique3d.file("unet_state_dict.pth")};
  for (auto& f : conditioning_model_files(base)) files.push_back(std::move(f));
  return files;
}

std::unique_ptr<NormalModel> NormalModel::load(const std::filesystem::path& image_variations,
                                               const std::filesystem::path& image2normal, Precision precision,
                                               const CheckpointReader& reader) {
  const DiffusersFolder base(image_variations);
  const DiffusersFolder unique3d(image2normal);
  const auto unet_config = base.component_config("unet");
  const auto base_unet_weights = base.component_weights("unet");
  const auto unet_weights = unique3d.file("unet_state_dict.pth");

  auto m = std::make_unique<NormalModel>();
  m->parts = load_conditioning_models(base, precision, reader);
  m->unet = std::make_unique<ReferenceUNet>(UNetConfig::from_json(read_json_file(unet_config), unet_config.string()),
                                            reader.options());
  TensorMap weights = reader.read(unet_weights);
  TensorMap reference = take_prefix(weights, kRefUnetPrefix);
  // Unique3D loads with strict=False; the one part its file may lack is the reference UNet.
  reader.apply(*m->unet->unet, std::move(weights), LoadPolicy{{std::string(kRefUnetPrefix) + "*"}, {}}, unet_weights.string());
  if (reference.empty())
    reader.load(*m->unet->reference, base_unet_weights);
  else
    reader.apply(*m->unet->reference, std::move(reference), {}, unet_weights.string() + " (" + kRefUnetPrefix + "*)");
  set_precision(*m->unet->unet, precision);  // the reference UNet is registered inside it
  return m;
}

torch::Tensor NormalModel::run(const std::vector<torch::Tensor>& views, const NormalSettings& s, NoiseSource& noise,
                               TensorMap* trace) {
  torch::NoGradGuard no_grad;
  ImageDiffusionModels models{parts.image_encoder, *parts.feature_extractor, parts.vae, *parts.scheduler,
                              [&](const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& embeddings,
                                  const torch::Tensor& condition) { return unet->forward(x, t, embeddings, condition); },
                              [this] { unet.reset(); }};
  ImageDiffusionSettings settings;
  settings.width = settings.height = settings.condition_width = settings.condition_height = s.size;
  settings.steps = s.steps;
  settings.guidance_scale = s.guidance_scale;
  settings.free_networks_as_done = s.free_networks_as_done;
  return run_image_diffusion(models, views, settings, noise, trace);
}

}  // namespace u3d::nn
