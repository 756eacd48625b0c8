#pragma once
// Unique3D's reference attention (the image2normal model) as a pair of attention processors sharing a
// store. A reference UNet runs first on the condition image: a ReferenceWriteProcessor on each of its
// attn1 modules records that module's input tokens under the module's name, then attends as usual. The
// main UNet runs next: a ReferenceReadProcessor on each attn1 takes the recorded tokens of the
// same-named module and adds a pixel-wise attention over them ("crosspond") to the ordinary
// self-attention. Pixel-wise means each token attends to exactly one key, the reference token at the
// same position, so the softmax is exactly 1 and the term is to_out(to_v(reference)); to_q and to_k are
// loaded but cannot change it. Official: custum_3d_diffusion/custum_modules/attention_processors.py,
// ExtraAttnProc with mode extract / inject, pixel_wise_crosspond, effect_on "all", chain "parralle".
#include <torch/torch.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "nn/layers/attention.h"

namespace u3d::nn {

// Tokens recorded by the reference pass, by processor name ("<attn1 module path>.processor").
struct ReferenceStore {
  std::map<std::string, torch::Tensor> states;
  // Where not empty, the recorded tokens hold one entry per distinct condition and group g of the main
  // UNet's input reads entry rows[g] (ReferenceUNet::forward: groups with identical inputs share one
  // pass); empty: group g reads entry g.
  std::vector<int64_t> rows;
  size_t writers = 0;  // write processors recording into this store (install_reference_attention)
  // When set, the write processor that completes `states` (every writer has recorded) ends the
  // reference pass by throwing ReferencePassComplete instead of attending: nothing the pass computes
  // after that input can reach a recorded token (ReferenceUNet::forward sets it and catches the throw).
  bool stop_when_recorded = false;
};

// Thrown by the write processor that completes the store when stop_when_recorded is set.
struct ReferencePassComplete {};

class ReferenceWriteProcessor : public AttentionProcessor {
 public:
  ReferenceWriteProcessor(std::shared_ptr<ReferenceStore> store, std::string name);
  torch::Tensor process(AttentionImpl& attention, const torch::Tensor& x, const torch::Tensor& context) override;

  std::shared_ptr<ReferenceStore> store;
  std::string name;
};

class ReferenceReadProcessor : public AttentionProcessor {
 public:
  // dim: the attention's query_dim; crosspond_attention is Attention(dim, heads 8, dim_head dim/8, biases).
  ReferenceReadProcessor(std::shared_ptr<ReferenceStore> store, std::string name, int64_t dim,
                         const torch::TensorOptions& options);
  // Takes (and removes) the recorded tokens [R, L, C]; x holds G·k entries in G groups of k consecutive
  // ones (the views of one object), group g using reference entry store->rows[g] (entry g where rows is
  // empty, G = R). The crosspond term is computed once per reference entry and added to every entry of
  // the groups that read it. A missing record or a shape that does not fit is an Error.
  torch::Tensor process(AttentionImpl& attention, const torch::Tensor& x, const torch::Tensor& context) override;

  std::shared_ptr<ReferenceStore> store;
  std::string name;
  Attention crosspond_attention{nullptr};
};

// Puts write processors (over `store`, counted in store->writers) on every attn1 of `reference` and read
// processors on every attn1 of `main`, named "<module path>.processor" as the official state dict does.
// Modules under a child named "ref_unet" are left alone. Returns the number of modules changed in `main`.
size_t install_reference_attention(torch::nn::Module& main, torch::nn::Module& reference,
                                   const std::shared_ptr<ReferenceStore>& store, const torch::TensorOptions& options);

}  // namespace u3d::nn
