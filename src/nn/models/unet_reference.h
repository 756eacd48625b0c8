#pragma once
// Unique3D's image2normal UNet: a main UNet2DConditionModel whose attn1 modules read the tokens a
// reference UNet records from the condition image (nn/layers/reference_attention.h). The reference UNet
// is registered as the main UNet's submodule "ref_unet", so `unet->named_parameters()` lists exactly the
// keys of the official unet_state_dict.pth: the main UNet's, its crosspond_attention weights, and
// "ref_unet.<plain UNet key>" (which the official file may omit; the reference is then the plain
// sd-image-variations UNet). Official: UnifieldWrappedUNet.unet_forward_hook in
// custum_3d_diffusion/custum_modules/unifield_processor.py.
#include <torch/torch.h>

#include <memory>

#include "nn/checkpoint/tensor_map.h"
#include "nn/layers/reference_attention.h"
#include "nn/models/unet.h"

namespace u3d::nn {

class ReferenceUNet {
 public:
  // Both UNets share `config`; the main one gets the read processors, the reference the write ones.
  ReferenceUNet(const UNetConfig& config, const torch::TensorOptions& options);

  // sample [N, C, H, W], timestep 0-dim or [N], encoder_hidden_states [N, L, D], condition_latents
  // [B, C, H, W] with N a multiple of B (N/B consecutive samples share one condition, e.g. the two
  // halves of classifier-free guidance or the views of one object). The reference pass runs on
  // (condition_latents, the first timestep and context of each group), once for groups whose three are
  // identical, and stops at the last input it records: its output would be discarded. When
  // `reference_states` is given it receives the recorded tokens by processor name, [B, L, C] each.
  torch::Tensor forward(const torch::Tensor& sample, const torch::Tensor& timestep,
                        const torch::Tensor& encoder_hidden_states, const torch::Tensor& condition_latents,
                        TensorMap* reference_states = nullptr);

  UNet2DConditionModel unet;       // the main UNet; its submodule "ref_unet" is `reference`
  UNet2DConditionModel reference;  // frozen reference UNet
  std::shared_ptr<ReferenceStore> store;
};

}  // namespace u3d::nn
