#pragma once
// IP-Adapter for SD 1.x (h94/IP-Adapter models/ip-adapter_sd15.safetensors, the file Unique3D's refinement
// loads through diffusers' load_ip_adapter): the image projection (Linear from the CLIP image embedding
// to `tokens` x cross_attention_dim, then LayerNorm) and the decoupled cross-attention on every attn2 of
// the UNet (nn/layers/ip_adapter_attention.h). The CLIP image encoder is ViT-H/14 (models/image_encoder,
// a CLIPVisionModelWithProjection: nn/models/clip_vision.h).
//
// Names: the file keeps the original layout, "image_proj.{proj,norm}.*" and "ip_adapter.<i>.to_k_ip.weight"
// / "to_v_ip.weight" with i the position of the attn2 module among all attention processors of the UNet
// in diffusers' attn_processors order (attn1 and attn2 alternate, so attn2 gets 1, 3, 5, ...). IpAdapter
// registers exactly these names, and the same Linear modules sit in the processors on the UNet, where
// they carry diffusers' names "<attn2>.processor.to_k_ip.0.weight".
#include <torch/torch.h>

#include <filesystem>
#include <memory>
#include <vector>

#include "nn/checkpoint/checkpoint_reader.h"
#include "nn/layers/ip_adapter_attention.h"
#include "nn/layers/layers.h"
#include "nn/models/unet.h"

namespace u3d::nn {

// tokens = norm(proj(image_embeds).reshape(N, tokens, cross_attention_dim)), LayerNorm eps 1e-5.
class IpImageProjectionImpl : public torch::nn::Module {
 public:
  IpImageProjectionImpl(int64_t image_embed_dim, int64_t cross_attention_dim, int64_t tokens,
                        const torch::TensorOptions& options);
  // image_embeds [N, image_embed_dim] -> [N, tokens, cross_attention_dim] in the input's dtype.
  torch::Tensor forward(const torch::Tensor& image_embeds);
  Linear proj{nullptr};
  LayerNorm norm{nullptr};
  int64_t tokens, cross_attention_dim;
};
TORCH_MODULE(IpImageProjection);

class IpAdapterImpl : public torch::nn::Module {
 public:
  // Puts an IpAdapterAttentionProcessor with `scale` on every attn2 module of `unet` (which keeps them
  // after this object is gone) and registers their projections under the original file's names.
  IpAdapterImpl(UNet2DConditionModelImpl& unet, int64_t image_embed_dim, int64_t tokens, double scale,
                const torch::TensorOptions& options);
  // diffusers' set_ip_adapter_scale.
  void set_scale(double scale);
  // The UNet's context: the text embeddings [N, L, D] followed by the image tokens of `image_embeds`
  // [N, image_embed_dim] -> [N, L + tokens, D], in the dtype of text_embeddings.
  torch::Tensor context(const torch::Tensor& text_embeddings, const torch::Tensor& image_embeds);

  IpImageProjection image_proj{nullptr};
  std::vector<std::shared_ptr<IpAdapterAttentionProcessor>> processors;
};
TORCH_MODULE(IpAdapter);

// Reads an adapter file in the original layout (safetensors or torch zip), sizes the adapter from its
// image_proj tensors, installs it on `unet` and loads it strictly (an Error names the file and tensor), or
// only checks it with a checking `reader` (the adapter is built on the UNet's device).
IpAdapter load_ip_adapter(UNet2DConditionModelImpl& unet, const std::filesystem::path& file, double scale,
                          const CheckpointReader& reader = {});

}  // namespace u3d::nn
