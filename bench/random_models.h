#pragma once
// A --models folder in the official layout (pipeline/model_folder.h, docs/models.md) with every network
// at its official size and random weights, for timing `generate` without the real checkpoints: the
// configs are the official ones (recorded in tests/data/nn/manifests), the weights random
// (randomize_keeping_activations) in fp16 (as the published fp16 files; the loaders convert), the
// Unique3D UNets as torch zip .pth files like
// the release's, the rest as safetensors. Models that the official folders share (the VAE, the CLIP
// image encoder, the plain UNet) are written once and hard-linked. About 11 GB; a "complete" marker
// is written last, so an interrupted run starts over.
#include <torch/torch.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "core/error.h"
#include "nn/checkpoint/config_json.h"
#include "nn/checkpoint/pth_writer.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/models/clip_text.h"
#include "nn/models/clip_vision.h"
#include "nn/models/controlnet.h"
#include "nn/models/ip_adapter.h"
#include "nn/models/rrdbnet.h"
#include "nn/models/unet.h"
#include "nn/models/unet_reference.h"
#include "nn/models/vae.h"

namespace u3d::bench {

namespace fs = std::filesystem;

inline fs::path test_data(const fs::path& relative) { return fs::path(UNIQUE3D_SOURCE_DIR) / "tests" / "data" / relative; }

inline nlohmann::json manifest_config(const std::string& name) {
  return nn::read_json_file(test_data("nn/manifests/" + name + ".json")).at("constructor_config");
}

inline void write_json_file(const fs::path& path, const nlohmann::json& json) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << json.dump(2);
}

// Random weights that keep the activations alive through a deep network, as the golden generators'
// randomize_: matrices and kernels N(0, 1/fan_in), other weights (norm scales) 1 + 0.1 N(0, 1), the
// rest (biases, embeddings of one vector) 0.1 N(0, 1). N(0, 0.02^2) everywhere made every norm scale
// nearly 0, so each network's output was one colour, and the normal maps' background key then left
// no object for the reconstruction.
inline void randomize_keeping_activations(torch::nn::Module& module) {
  torch::NoGradGuard no_grad;
  for (auto& p : module.named_parameters(true)) {
    torch::Tensor t = p.value();
    const std::string& name = p.key();
    if (t.dim() >= 2) t.normal_(0.0, 1.0 / std::sqrt(double(t.numel() / t.size(0))));
    else if (name.size() >= 6 && name.compare(name.size() - 6, 6, "weight") == 0) t.normal_(1.0, 0.1);
    else t.normal_(0.0, 0.1);
  }
}

// The module's parameters, randomised, in fp16.
inline nn::TensorMap random_fp16_weights(torch::nn::Module& module) {
  randomize_keeping_activations(module);
  nn::TensorMap out;
  for (const auto& p : module.named_parameters(true)) out[p.key()] = p.value().detach().to(torch::kHalf);
  for (const auto& b : module.named_buffers(true)) out[b.key()] = b.value().detach().clone();
  return out;
}

// Writes `weights` at `path` unless the file is already there (a rerun after an interruption).
inline void write_weights(const fs::path& path, const std::function<nn::TensorMap()>& weights, bool torch_zip = false) {
  if (fs::exists(path)) return;
  std::fprintf(stderr, "[random models] writing %s\n", path.c_str());
  fs::create_directories(path.parent_path());
  torch::NoGradGuard no_grad;
  const nn::TensorMap tensors = weights();
  if (torch_zip) nn::save_pth(tensors, path);
  else nn::save_safetensors(tensors, path);
}

inline void link_file(const fs::path& from, const fs::path& to) {
  if (fs::exists(to)) return;
  fs::create_directories(to.parent_path());
  fs::create_hard_link(from, to);
}

// The official merges of the CLIP tokenizer (tokenizer/merges.txt), from the gzipped vocabulary.
inline void write_merges(const fs::path& path) {
  if (fs::exists(path)) return;
  gzFile gz = gzopen(test_data("nn/clip_tokenizer/bpe_simple_vocab_16e6.txt.gz").c_str(), "rb");
  if (!gz) throw Error("cannot read the CLIP vocabulary in tests/data/nn/clip_tokenizer");
  std::string merges;
  char buffer[1 << 16];
  for (int n; (n = gzread(gz, buffer, sizeof(buffer))) > 0;) merges.append(buffer, size_t(n));
  gzclose(gz);
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << merges;
}

inline void write_random_model_folder(const fs::path& root) {
  if (fs::exists(root / "complete")) return;
  torch::manual_seed(0);
  const torch::TensorOptions cpu;

  // The parts of sd-image-variations (img2mvimg/ and image2normal/ are whole diffusers folders of it).
  const nlohmann::json unet_json = manifest_config("unet_sd_image_variations_plain");
  const nlohmann::json vae_json = manifest_config("vae_sd1x");
  const nlohmann::json clip_json = manifest_config("clip_vision_vit_l14_with_projection");
  const nn::UNetConfig unet_config = nn::UNetConfig::from_json(unet_json, "unet");
  const fs::path base = root / "stable-diffusion-v1-5";
  const fs::path mv = root / "img2mvimg", normal = root / "image2normal";
  write_weights(base / "unet" / "diffusion_pytorch_model.safetensors", [&] {
    nn::UNet2DConditionModel unet(unet_config, cpu);
    return random_fp16_weights(*unet);
  });
  write_weights(base / "vae" / "diffusion_pytorch_model.safetensors", [&] {
    nn::AutoencoderKL vae(nn::AutoencoderKLConfig::from_json(vae_json, "vae"), cpu);
    return random_fp16_weights(*vae);
  });
  write_weights(mv / "image_encoder" / "model.safetensors", [&] {
    nn::ClipVisionModelWithProjection clip(nn::ClipVisionConfig::from_json(clip_json, "clip"), cpu);
    return random_fp16_weights(*clip);
  });
  for (const fs::path& folder : {mv, normal}) {
    write_json_file(folder / "unet" / "config.json", unet_json);
    write_json_file(folder / "vae" / "config.json", vae_json);
    write_json_file(folder / "image_encoder" / "config.json", clip_json);
    fs::create_directories(folder / "feature_extractor");
    fs::copy_file(test_data("nn/clip_vision/preprocessor_config.json"), folder / "feature_extractor" / "preprocessor_config.json",
                  fs::copy_options::overwrite_existing);
    fs::create_directories(folder / "scheduler");
    fs::copy_file(test_data("nn/scheduler/sd_scheduler_config.json"), folder / "scheduler" / "scheduler_config.json",
                  fs::copy_options::overwrite_existing);
    link_file(base / "vae" / "diffusion_pytorch_model.safetensors", folder / "vae" / "diffusion_pytorch_model.safetensors");
  }
  link_file(mv / "image_encoder" / "model.safetensors", normal / "image_encoder" / "model.safetensors");
  link_file(base / "unet" / "diffusion_pytorch_model.safetensors", normal / "unet" / "diffusion_pytorch_model.safetensors");

  // The Unique3D UNets: 8-channel conv_in and class labels; the normal UNet with its reference UNet.
  write_weights(
      mv / "unet_state_dict.pth",
      [&] {
        nn::UNet2DConditionModel unet(nn::UNetConfig::from_json(manifest_config("unet_unique3d_img2mvimg"), "unet"), cpu);
        return random_fp16_weights(*unet);
      },
      /*torch_zip=*/true);
  write_weights(
      normal / "unet_state_dict.pth",
      [&] {
        nn::ReferenceUNet unet(nn::UNetConfig::from_json(manifest_config("unet_unique3d_image2normal"), "unet"), cpu);
        return random_fp16_weights(*unet.unet);
      },
      /*torch_zip=*/true);

  // The refinement: SD 1.5 (its UNet and VAE above), the tile ControlNet, the IP-Adapter with ViT-H/14.
  write_json_file(base / "unet" / "config.json", unet_json);
  write_json_file(base / "vae" / "config.json", vae_json);
  const nlohmann::json text_json = manifest_config("clip_text_vit_l14_sd15");
  write_json_file(base / "text_encoder" / "config.json", text_json);
  write_weights(base / "text_encoder" / "model.safetensors", [&] {
    nn::ClipTextModel text(nn::ClipTextConfig::from_json(text_json, "text"), cpu);
    return random_fp16_weights(*text);
  });
  write_merges(base / "tokenizer" / "merges.txt");
  fs::create_directories(base / "feature_extractor");
  fs::copy_file(test_data("nn/clip_vision/preprocessor_config.json"), base / "feature_extractor" / "preprocessor_config.json",
                fs::copy_options::overwrite_existing);
  fs::create_directories(base / "scheduler");
  fs::copy_file(test_data("nn/scheduler/sd_scheduler_config.json"), base / "scheduler" / "scheduler_config.json",
                fs::copy_options::overwrite_existing);
  const nlohmann::json controlnet_json = manifest_config("controlnet_sd15");
  write_json_file(root / "controlnet-tile" / "config.json", controlnet_json);
  write_weights(root / "controlnet-tile" / "diffusion_pytorch_model.safetensors", [&] {
    nn::ControlNetModel controlnet(nn::ControlNetConfig::from_json(controlnet_json, "controlnet"), cpu);
    return random_fp16_weights(*controlnet);
  });
  // h94/IP-Adapter models/image_encoder: OpenCLIP ViT-H/14 as transformers' CLIPVisionModelWithProjection.
  nlohmann::json vit_h = clip_json;
  vit_h["hidden_size"] = 1280;
  vit_h["intermediate_size"] = 5120;
  vit_h["num_attention_heads"] = 16;
  vit_h["num_hidden_layers"] = 32;
  vit_h["projection_dim"] = 1024;
  vit_h["hidden_act"] = "gelu";
  const fs::path ip = root / "IP-Adapter" / "models";
  write_json_file(ip / "image_encoder" / "config.json", vit_h);
  write_weights(ip / "image_encoder" / "model.safetensors", [&] {
    nn::ClipVisionModelWithProjection clip(nn::ClipVisionConfig::from_json(vit_h, "clip"), cpu);
    return random_fp16_weights(*clip);
  });
  write_weights(ip / "ip-adapter_sd15.safetensors", [&] {
    nn::UNet2DConditionModel unet(unet_config, torch::TensorOptions().device(torch::kMeta));
    nn::IpAdapter adapter(*unet, 1024, 4, 1.0, cpu);
    return random_fp16_weights(*adapter);
  });

  // Real-ESRGAN x4plus as basicsr saves it (torch zip, under params_ema).
  write_weights(
      root / "RealESRGAN_x4plus.pth",
      [&] {
        nn::RRDBNet net(nn::RRDBNetConfig{}, cpu);
        nn::TensorMap out;
        for (auto& [key, tensor] : random_fp16_weights(*net)) out["params_ema." + key] = tensor;
        return out;
      },
      /*torch_zip=*/true);
  std::ofstream(root / "complete") << "written by bench_pipeline\n";
}

}  // namespace u3d::bench
