#include "nn/models/ip_adapter.h"

#include "core/error.h"
#include "nn/checkpoint/diffusers_folder.h"
#include "nn/checkpoint/state_dict_loader.h"

namespace u3d::nn {

IpImageProjectionImpl::IpImageProjectionImpl(int64_t image_embed_dim, int64_t cross_dim, int64_t tokens_,
                                             const torch::TensorOptions& t)
    : tokens(tokens_), cross_attention_dim(cross_dim) {
  proj = register_module("proj", Linear(image_embed_dim, tokens * cross_dim, true, t));
  norm = register_module("norm", LayerNorm(cross_dim, 1e-5, t));
}

torch::Tensor IpImageProjectionImpl::forward(const torch::Tensor& image_embeds) {
  if (image_embeds.dim() != 2 || image_embeds.size(1) != proj->weight.size(1))
    throw Error("IP-Adapter: image embeddings must be [N, " + std::to_string(proj->weight.size(1)) + "], got " +
                c10::str(image_embeds.sizes()));
  torch::Tensor h = proj->forward(image_embeds.to(proj->weight.scalar_type()));
  return norm->forward(h.reshape({image_embeds.size(0), tokens, cross_attention_dim})).to(image_embeds.scalar_type());
}

IpAdapterImpl::IpAdapterImpl(UNet2DConditionModelImpl& unet, int64_t image_embed_dim, int64_t tokens, double scale,
                             const torch::TensorOptions& t) {
  const int64_t cross_dim = unet.config.cross_attention_dim[0];
  for (int64_t d : unet.config.cross_attention_dim)
    if (d != cross_dim) throw Error("IP-Adapter: the UNet's cross-attention dims differ between blocks");
  image_proj = register_module("image_proj", IpImageProjection(image_embed_dim, cross_dim, tokens, t));
  auto layers = register_module("ip_adapter", std::make_shared<torch::nn::Module>());
  // diffusers' attn_processors order is the modules' registration order, which UNet2DConditionModel
  // follows; every Attention module counts, attn1 included.
  int64_t index = 0;
  for (const auto& item : unet.named_modules("", /*include_self=*/false)) {
    auto* attention = dynamic_cast<AttentionImpl*>(item.value().get());
    if (!attention) continue;
    if (item.key().ends_with(".attn2")) {
      auto processor = std::make_shared<IpAdapterAttentionProcessor>(*attention, tokens, scale, t);
      auto entry = layers->register_module(std::to_string(index), std::make_shared<torch::nn::Module>());
      entry->register_module("to_k_ip", processor->to_k_ip);
      entry->register_module("to_v_ip", processor->to_v_ip);
      processors.push_back(processor);
      attention->set_processor(processor);
    }
    ++index;
  }
  if (processors.empty()) throw Error("IP-Adapter: the UNet has no cross-attention (attn2) modules");
}

void IpAdapterImpl::set_scale(double scale) {
  for (auto& p : processors) p->scale = scale;
}

torch::Tensor IpAdapterImpl::context(const torch::Tensor& text_embeddings, const torch::Tensor& image_embeds) {
  if (text_embeddings.dim() != 3 || text_embeddings.size(0) != image_embeds.size(0))
    throw Error("IP-Adapter: text embeddings " + c10::str(text_embeddings.sizes()) + " and image embeddings " +
                c10::str(image_embeds.sizes()) + " do not pair up");
  return torch::cat({text_embeddings, image_proj->forward(image_embeds).to(text_embeddings.scalar_type())}, 1);
}

IpAdapter load_ip_adapter(UNet2DConditionModelImpl& unet, const std::filesystem::path& file, double scale,
                          const CheckpointReader& reader) {
  const TensorMap weights = reader.read(file);
  const auto proj = weights.find("image_proj.proj.weight");
  const auto norm = weights.find("image_proj.norm.weight");
  if (proj == weights.end() || norm == weights.end() || proj->second.dim() != 2 || norm->second.dim() != 1 ||
      norm->second.size(0) == 0 || proj->second.size(0) % norm->second.size(0) != 0)
    throw Error(file.string() + ": not an IP-Adapter file in the original layout (image_proj.proj.weight [tokens x "
                "cross dim, image dim] and image_proj.norm.weight [cross dim])");
  const int64_t cross_dim = norm->second.size(0);
  if (cross_dim != unet.config.cross_attention_dim[0])
    throw Error(file.string() + ": image_proj.norm.weight has " + std::to_string(cross_dim) +
                " entries, the UNet's cross-attention dim is " + std::to_string(unet.config.cross_attention_dim[0]));
  IpAdapter adapter(unet, proj->second.size(1), proj->second.size(0) / cross_dim, scale,
                    torch::TensorOptions().device(unet.conv_in->weight.device()));
  reader.apply(*adapter, weights, {}, file.string());
  return adapter;
}

}  // namespace u3d::nn
