#include "nn/layers/reference_attention.h"

#include <algorithm>
#include <utility>

#include "core/error.h"

namespace u3d::nn {

namespace {

bool is_self_attention_name(const std::string& name) { return name == "attn1" || name.ends_with(".attn1"); }

bool under_ref_unet(const std::string& name) { return name == "ref_unet" || name.starts_with("ref_unet."); }

}  // namespace

ReferenceWriteProcessor::ReferenceWriteProcessor(std::shared_ptr<ReferenceStore> store_, std::string name_)
    : store(std::move(store_)), name(std::move(name_)) {
  TORCH_CHECK(store, "reference attention: the store must not be null");
}

torch::Tensor ReferenceWriteProcessor::process(AttentionImpl& attention, const torch::Tensor& x,
                                               const torch::Tensor& context) {
  store->states[name] = x;
  if (store->stop_when_recorded && store->states.size() == store->writers) throw ReferencePassComplete{};
  return attention.attend(x, context.defined() ? context : x);
}

ReferenceReadProcessor::ReferenceReadProcessor(std::shared_ptr<ReferenceStore> store_, std::string name_, int64_t dim,
                                               const torch::TensorOptions& options)
    : store(std::move(store_)), name(std::move(name_)) {
  TORCH_CHECK(store, "reference attention: the store must not be null");
  TORCH_CHECK(dim % 8 == 0, "reference attention: ", dim, " channels do not split into 8 heads");
  AttentionOptions o;
  o.query_dim = dim;
  o.heads = 8;
  o.dim_head = dim / 8;
  o.qkv_bias = true;
  crosspond_attention = register_module("crosspond_attention", Attention(o, options));
}

torch::Tensor ReferenceReadProcessor::process(AttentionImpl& attention, const torch::Tensor& x,
                                              const torch::Tensor& context) {
  auto it = store->states.find(name);
  if (it == store->states.end())
    throw Error("reference attention: no reference tokens recorded for " + name + " (run the reference pass first)");
  const torch::Tensor reference = std::move(it->second);
  store->states.erase(it);
  const std::vector<int64_t>& rows = store->rows;
  const int64_t groups = rows.empty() ? reference.size(0) : int64_t(rows.size());
  const bool rows_fit = std::all_of(rows.begin(), rows.end(), [&](int64_t r) { return r >= 0 && r < reference.size(0); });
  if (reference.dim() != 3 || reference.size(0) == 0 || !rows_fit || x.dim() != 3 || x.size(0) % groups != 0 ||
      reference.size(1) != x.size(1) || reference.size(2) != x.size(2))
    throw Error("reference attention: reference tokens " + c10::str(reference.sizes()) + " do not fit the input " +
                c10::str(x.sizes()) + " at " + name);
  // One key per query: softmax = 1, so the attention output is the projected value, the same for every
  // entry that reads one reference entry: computed once per reference entry.
  const torch::Tensor term =
      crosspond_attention->out_proj->forward(crosspond_attention->to_v->forward(reference.to(x.scalar_type())));
  torch::Tensor out = attention.attend(x, context.defined() ? context : x);
  const int64_t per_group = x.size(0) / groups;
  for (int64_t g = 0; g < groups; ++g)
    out.narrow(0, g * per_group, per_group).add_(term.narrow(0, rows.empty() ? g : rows[size_t(g)], 1));
  return out;
}

size_t install_reference_attention(torch::nn::Module& main, torch::nn::Module& reference,
                                   const std::shared_ptr<ReferenceStore>& store, const torch::TensorOptions& options) {
  store->writers = set_attention_processors(reference, [&](const std::string& name, const AttentionImpl&) -> std::shared_ptr<AttentionProcessor> {
    if (!is_self_attention_name(name) || under_ref_unet(name)) return nullptr;
    return std::make_shared<ReferenceWriteProcessor>(store, name + ".processor");
  });
  return set_attention_processors(main, [&](const std::string& name, const AttentionImpl& attention) -> std::shared_ptr<AttentionProcessor> {
    if (!is_self_attention_name(name) || under_ref_unet(name)) return nullptr;
    return std::make_shared<ReferenceReadProcessor>(store, name + ".processor", attention.options.query_dim, options);
  });
}

}  // namespace u3d::nn
