#pragma once
// The refinement stage's folders in the official layouts (Stable Diffusion 1.5 base, Unique3D's
// ckpt/controlnet-tile, h94/IP-Adapter), made of tiny models: the golden UNet, VAE, CLIP image encoder and
// IP-Adapter, plus a seeded random text encoder (the tokenizer's full vocabulary, 16 wide to fit the UNet)
// and ControlNet (one conditioning downsampling to fit the tiny VAE).
#include <zlib.h>

#include <filesystem>
#include <fstream>

#include "golden.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/pipelines/unique3d_refine.h"

namespace u3d::nn::test {

inline TensorMap seeded_weights(torch::nn::Module& module) {
  randomize_parameters(module, 0.2);
  TensorMap out;
  for (const auto& p : module.named_parameters(true)) out[p.key()] = p.value().detach().clone();
  return out;
}

inline void write_json(const std::filesystem::path& path, const nlohmann::json& json) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << json.dump(2);
}

// Writes the three folders of `paths`. Uses torch's global generator (seeded here).
inline void write_tiny_refine_folders(const RefineCheckpoints& paths) {
  namespace fs = std::filesystem;
  torch::NoGradGuard no_grad;
  torch::manual_seed(0);
  copy_into_folder(
      paths.base,
      {{golden_dir("unet_base") / "config.json", "unet/config.json"},
       {golden_dir("unet_base") / "weights.safetensors", "unet/diffusion_pytorch_model.safetensors"},
       {golden_dir("vae") / "config.json", "vae/config.json"},
       {golden_dir("vae") / "weights.safetensors", "vae/diffusion_pytorch_model.safetensors"},
       {golden_dir("clip_vision") / "preprocessor_config_tiny32.json", "feature_extractor/preprocessor_config.json"},
       {golden_dir("scheduler") / "sd_scheduler_config.json", "scheduler/scheduler_config.json"}});
  // tokenizer/merges.txt: the openai merges uncompressed, as transformers' CLIPTokenizer files hold them.
  gzFile gz = gzopen((golden_dir("clip_tokenizer") / "bpe_simple_vocab_16e6.txt.gz").c_str(), "rb");
  if (!gz) throw Error("cannot read the tiny tokenizer vocabulary");
  std::string merges;
  char buffer[1 << 16];
  for (int n; (n = gzread(gz, buffer, sizeof(buffer))) > 0;) merges.append(buffer, size_t(n));
  gzclose(gz);
  fs::create_directories(paths.base / "tokenizer");
  std::ofstream(paths.base / "tokenizer" / "merges.txt", std::ios::binary) << merges;

  nlohmann::json text = golden_config("clip_text");
  text["vocab_size"] = 49408;
  text["hidden_size"] = 16;
  write_json(paths.base / "text_encoder" / "config.json", text);
  ClipTextModel text_encoder(ClipTextConfig::from_json(text, "text"), torch::TensorOptions());
  save_safetensors(seeded_weights(*text_encoder), paths.base / "text_encoder" / "model.safetensors");

  nlohmann::json controlnet_config = golden_config("controlnet");
  controlnet_config["conditioning_embedding_out_channels"] = {8, 16};
  write_json(paths.ckpt / "controlnet-tile" / "config.json", controlnet_config);
  ControlNetModel controlnet(ControlNetConfig::from_json(controlnet_config, "controlnet"), torch::TensorOptions());
  save_safetensors(seeded_weights(*controlnet), paths.ckpt / "controlnet-tile" / "diffusion_pytorch_model.safetensors");

  copy_into_folder(paths.ip_adapter,
                   {{golden_dir("clip_vision") / "config.json", "models/image_encoder/config.json"},
                    {golden_dir("clip_vision") / "weights.safetensors", "models/image_encoder/model.safetensors"},
                    {golden_dir("ip_adapter") / "weights.safetensors", "models/ip-adapter_sd15.safetensors"}});
}

}  // namespace u3d::nn::test
