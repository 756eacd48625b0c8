#include "nn/models/unet_reference.h"

#include <vector>

#include "core/error.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

ReferenceUNet::ReferenceUNet(const UNetConfig& config, const torch::TensorOptions& options)
    : unet(config, options), reference(config, options), store(std::make_shared<ReferenceStore>()) {
  install_reference_attention(*unet, *reference, store, options);
  unet->register_module("ref_unet", reference.ptr());
}

namespace {

// Equal bit for bit (not merely ==: -0 and +0 differ), so that equal inputs give equal results.
bool identical(const torch::Tensor& a, const torch::Tensor& b) {
  if (a.sizes() != b.sizes() || a.scalar_type() != b.scalar_type()) return false;
  const torch::ScalarType bits = a.element_size() == 8   ? torch::kLong
                                 : a.element_size() == 4 ? torch::kInt
                                 : a.element_size() == 2 ? torch::kShort
                                                         : torch::kByte;
  return torch::equal(a.contiguous().view(bits), b.contiguous().view(bits));
}

}  // namespace

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
  const bool steps_per_group = steps.dim() > 0 && steps.numel() > 1;
  if (steps_per_group) {
    if (steps.numel() != sample.size(0))
      throw Error("reference UNet: " + std::to_string(steps.numel()) + " timesteps for a batch of " +
                  std::to_string(sample.size(0)));
    steps = steps.reshape({groups, -1}).select(1, 0);
  }
  // Groups whose reference inputs (condition latents, context, timestep) are identical share one
  // reference pass: each sample of the pass is computed on its own, so their recorded tokens would be
  // the same values (bit for bit in bf16; in fp32 ATen's convolutions round differently at another
  // batch size, docs/networks.md). With guidance the unconditional half gives every view zero
  // condition latents and a zero context (nn/pipelines/image_diffusion.h), so its pass runs once
  // instead of once a view.
  std::vector<int64_t> distinct, row_of_group;
  for (int64_t g = 0; g < groups; ++g) {
    size_t row = 0;
    while (row < distinct.size() &&
           !(identical(condition_latents[g], condition_latents[distinct[row]]) &&
             identical(context[g], context[distinct[row]]) &&
             (!steps_per_group || identical(steps[g], steps[distinct[row]]))))
      ++row;
    if (row == distinct.size()) distinct.push_back(g);
    row_of_group.push_back(int64_t(row));
  }
  torch::Tensor pass_latents = condition_latents, pass_context = context, pass_steps = steps;
  if (int64_t(distinct.size()) < groups) {
    const torch::Tensor rows = torch::tensor(distinct, torch::kLong);
    pass_latents = condition_latents.index_select(0, rows);
    pass_context = context.index_select(0, rows);
    if (steps_per_group) pass_steps = steps.index_select(0, rows);
  }

  store->states.clear();
  store->rows.clear();
  // The pass ends with the last input it records (ReferenceStore::stop_when_recorded): the rest of the
  // reference UNet (in SD 1.x that last attn1's attention, its block's cross-attention and feed-forward,
  // proj_out and conv_out at full resolution) gives an output nobody reads.
  store->stop_when_recorded = true;
  try {
    reference->forward(pass_latents, pass_steps, pass_context);
  } catch (const ReferencePassComplete&) {
  } catch (...) {
    store->stop_when_recorded = false;
    store->states.clear();
    store->rows.clear();
    throw;
  }
  store->stop_when_recorded = false;
  // The shared entries stay shared: each read processor projects an entry once for all the groups that
  // read it (ReferenceStore::rows).
  if (int64_t(distinct.size()) < groups) store->rows = row_of_group;
  if (reference_states) {
    const torch::Tensor rows = torch::tensor(row_of_group, torch::kLong);
    for (const auto& [name, tokens] : store->states)
      (*reference_states)[name] = store->rows.empty() ? tokens : tokens.index_select(0, rows);
  }
  torch::Tensor out;
  try {
    out = unet->forward(sample, timestep, encoder_hidden_states);
  } catch (...) {
    store->states.clear();
    store->rows.clear();
    throw;
  }
  store->states.clear();
  store->rows.clear();
  return out;
}

}  // namespace u3d::nn
