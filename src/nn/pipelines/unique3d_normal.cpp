#include "nn/pipelines/unique3d_normal.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/layers/layers.h"

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

namespace {

std::unique_ptr<ReferenceUNet> load_reference_unet(const DiffusersFolder& base, const DiffusersFolder& unique3d,
                                                   Precision precision, const CheckpointReader& reader) {
  const auto unet_config = base.component_config("unet");
  const auto base_unet_weights = base.component_weights("unet");
  const auto unet_weights = unique3d.file("unet_state_dict.pth");
  auto unet = std::make_unique<ReferenceUNet>(UNetConfig::from_json(read_json_file(unet_config), unet_config.string()),
                                              reader.options());
  allocate_in_precision(*unet->unet, precision);  // the reference UNet is registered inside it
  TensorMap weights = reader.read(unet_weights);
  TensorMap reference = take_prefix(weights, kRefUnetPrefix);
  // Unique3D loads with strict=False; the one part its file may lack is the reference UNet.
  reader.apply(*unet->unet, std::move(weights), LoadPolicy{{std::string(kRefUnetPrefix) + "*"}, {}},
               unet_weights.string());
  if (reference.empty())
    reader.load(*unet->reference, base_unet_weights);
  else
    reader.apply(*unet->reference, std::move(reference), {}, unet_weights.string() + " (" + kRefUnetPrefix + "*)");
  pack_weights_in_place(*unet->unet);  // the reference UNet is registered inside it
  return unet;
}

ImageDiffusionSettings diffusion_settings(const NormalSettings& s) {
  ImageDiffusionSettings settings;
  settings.width = settings.height = settings.condition_width = settings.condition_height = s.size;
  settings.steps = s.steps;
  settings.guidance_scale = s.guidance_scale;
  settings.free_networks_as_done = s.free_networks_as_done;
  return settings;
}

}  // namespace

std::unique_ptr<NormalModel> NormalModel::load_conditioning(const std::filesystem::path& image_variations,
                                                            const std::filesystem::path& image2normal,
                                                            Precision precision) {
  files(image_variations, image2normal);  // every file, the UNets' too, before any weights are read
  auto m = std::make_unique<NormalModel>();
  m->image_variations_ = image_variations;
  m->image2normal_ = image2normal;
  m->precision_ = precision;
  m->parts = load_conditioning_models(DiffusersFolder(image_variations), precision);
  return m;
}

std::unique_ptr<NormalModel> NormalModel::load(const std::filesystem::path& image_variations,
                                               const std::filesystem::path& image2normal, Precision precision,
                                               const CheckpointReader& reader) {
  const DiffusersFolder base(image_variations);
  const DiffusersFolder unique3d(image2normal);
  files(image_variations, image2normal);
  auto m = std::make_unique<NormalModel>();
  m->image_variations_ = image_variations;
  m->image2normal_ = image2normal;
  m->precision_ = precision;
  m->parts = load_conditioning_models(base, precision, reader);
  m->unet = load_reference_unet(base, unique3d, precision, reader);
  return m;
}

void NormalModel::load_unet() {
  if (!unet)
    unet = load_reference_unet(DiffusersFolder(image_variations_), DiffusersFolder(image2normal_), precision_, {});
}

ImageDiffusionModels NormalModel::models() {
  return {parts.image_encoder,
          *parts.feature_extractor,
          parts.vae,
          *parts.scheduler,
          [this](const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& embeddings,
                 const torch::Tensor& condition) { return unet->forward(x, t, embeddings, condition); },
          [this] { unet.reset(); }};
}

ImageConditions NormalModel::encode(const std::vector<torch::Tensor>& views, const NormalSettings& s,
                                    TensorMap* trace) {
  return encode_image_conditions(models(), views, diffusion_settings(s), trace);
}

torch::Tensor NormalModel::sample(const ImageConditions& conditions, const NormalSettings& s, NoiseSource& noise,
                                  TensorMap* trace) {
  if (!unet)
    throw Error(
        "normal model: its UNets are not loaded (load_unet) or were freed by an earlier run "
        "(free_networks_as_done)");
  return sample_image_diffusion(models(), conditions, diffusion_settings(s), noise, trace);
}

torch::Tensor NormalModel::run(const std::vector<torch::Tensor>& views, const NormalSettings& s, NoiseSource& noise,
                               TensorMap* trace) {
  const ImageConditions conditions = encode(views, s, trace);
  load_unet();
  return sample(conditions, s, noise, trace);
}

}  // namespace u3d::nn
