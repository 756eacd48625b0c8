#include "nn/models/unet_reference.h"

#include "core/error.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

ReferenceUNet::ReferenceUNet(const UNetConfig& config, const torch::TensorOptions& options)
    : unet(config, options), reference(config, options), store(std::make_shared<ReferenceStore>()) {
  install_reference_attention(*unet, *reference, store, options);
  unet->register_module("ref_unet", reference.ptr());
  // In bf16 the packed convolution weights of both UNets (about 1 GB each) put the normal stage over
  // 6 GB; the reference UNet reorders its weights on every call instead (docs/networks.md, "bf16 kernels").
  keep_packed_conv_weights(*reference, false);
}

torch::Tensor ReferenceUNet::forward(const torch::Tensor& sample, const torch::Tensor& timestep,
                                     const torch::Tensor& encoder_hidden_states, const torch::Tensor& condition_latents,
                                     TensorMap* reference_states) {
  if (sample.dim() != 4 || condition_latents.dim() != 4 || condition_latents.size(0) == 0 ||
      sample.size(0) % condition_latents.size(0) != 0 || condition_latents.sizes().slice(1) != sample.sizes().slice(1))
    throw Error("reference UNet: condition_latents " + c10::str(condition_latents.sizes()) +
                " must be [B, C, H, W] like the sample " + c10::str(sample.sizes()) + " with a batch dividing it");
  if (encoder_hidden_states.dim() != 3 || encoder_hidden_states.size(0) != sample.size(0))
    throw Error("reference UNet: encoder_hidden_states must be [" + std::to_string(sample.size(0)) + ", L, C], got " +
                c10::str(encoder_hidden_states.sizes()));
  const int64_t groups = condition_latents.size(0);
  // The first context and timestep of each group of N/B samples, as the official hook takes them.
  const torch::Tensor context = encoder_hidden_states.reshape({groups, -1, encoder_hidden_states.size(1),
                                                               encoder_hidden_states.size(2)}).select(1, 0);
  torch::Tensor steps = timestep;
  if (steps.dim() > 0 && steps.numel() > 1) {
    if (steps.numel() != sample.size(0))
      throw Error("reference UNet: " + std::to_string(steps.numel()) + " timesteps for a batch of " +
                  std::to_string(sample.size(0)));
    steps = steps.reshape({groups, -1}).select(1, 0);
  }
  store->states.clear();
  reference->forward(condition_latents, steps, context);
  if (reference_states)
    for (const auto& [name, tokens] : store->states) (*reference_states)[name] = tokens;
  torch::Tensor out;
  try {
    out = unet->forward(sample, timestep, encoder_hidden_states);
  } catch (...) {
    store->states.clear();
    throw;
  }
  store->states.clear();
  return out;
}

}  // namespace u3d::nn
