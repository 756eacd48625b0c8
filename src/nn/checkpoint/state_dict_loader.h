#pragma once
// Copies a checkpoint (TensorMap) into a torch::nn::Module by key, strictly: every parameter and
// buffer of the module must be in the file, every tensor of the file must be used, shapes must agree
// and dtypes must be of the same kind (floating <-> floating and integer <-> integer are converted,
// e.g. fp16/bf16 checkpoints into an fp32 model; float into an integer buffer is an error). Exceptions
// are stated per model in a LoadPolicy, and every mismatch is reported in one u3d::Error that names
// the checkpoint and each offending tensor.
//
// Keys that may legitimately be absent or extra in the checkpoints Unique3D uses:
//  - CLIP (image_encoder, text_encoder): `*.embeddings.position_ids` is a buffer older transformers
//    saved and newer ones do not; it is redundant (arange) and ignored when present: clip_policy().
//  - VAE: files written by diffusers < 0.14 (the sd-image-variations vae among them) name the
//    mid-block attention `query/key/value/proj_attn`; they are accepted as `to_q/to_k/to_v/to_out.0`,
//    and 1x1-conv-shaped projection weights [C, C, 1, 1] as Linear [C, C]. Always on.
//  - Unique3D UNets (ckpt/img2mvimg, ckpt/image2normal unet_state_dict.pth; Unique3D loads them with
//    strict=False): the image2normal state dict may or may not contain the reference UNet under
//    `ref_unet.` (686 tensors). Split it off with take_prefix(weights, kRefUnetPrefix) before loading the
//    main UNet; when it is absent, the reference UNet is the plain sd-image-variations UNet. Apart from
//    that the files match the model exactly (class_embedding.weight and the 8-channel conv_in for
//    img2mvimg, the crosspond_attention projections for image2normal), so they load strictly.
#include <torch/torch.h>

#include <string>
#include <vector>

#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

struct LoadPolicy {
  // Glob patterns ('*' matches any run of characters, dots included) over the module's keys that the
  // file may lack; such tensors keep their current values.
  std::vector<std::string> may_be_missing;
  // Glob patterns over file keys that the module does not use; such tensors are skipped.
  std::vector<std::string> may_be_unexpected;
};

struct LoadReport {
  int loaded = 0;
  std::vector<std::string> missing_allowed;     // module keys absent from the file, per may_be_missing
  std::vector<std::string> ignored;             // file keys skipped, per may_be_unexpected
  std::vector<std::string> renamed;             // "legacy -> new" key renames applied
  std::vector<std::string> converted;           // "key: BFloat16 -> Float" dtype conversions
};

inline constexpr const char* kRefUnetPrefix = "ref_unet.";

LoadPolicy clip_policy();

// True when `key` matches the glob `pattern` ('*' = any run of characters).
bool key_matches(const std::string& pattern, const std::string& key);

// Moves every tensor whose key starts with `prefix` out of `weights` and returns them with the prefix
// stripped (e.g. the reference UNet of a Unique3D image2normal checkpoint).
TensorMap take_prefix(TensorMap& weights, const std::string& prefix);

// Copies `weights` into `module`'s parameters and buffers (keys as in named_parameters() /
// named_buffers()), converting dtypes as described above, without recording gradients. `source` names
// the checkpoint in errors. Nothing is copied when the check fails. Takes the map by value and drops
// each tensor once it is copied: a map moved in is freed as the module fills, so loading needs little
// more memory than the module itself (the module's pages are only touched as they are written).
LoadReport load_state_dict(torch::nn::Module& module, TensorMap weights, const LoadPolicy& policy,
                           const std::string& source);

// The same checks without copying anything: `weights` may be meta tensors (inspect_weights_file).
LoadReport check_state_dict(torch::nn::Module& module, const TensorMap& weights, const LoadPolicy& policy,
                            const std::string& source);

}  // namespace u3d::nn
