#include "nn/checkpoint/state_dict_loader.h"

#include <map>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "core/memory.h"

namespace u3d::nn {
namespace {

// diffusers < 0.14 names of the VAE mid-block attention projections, and their current names.
const std::pair<const char*, const char*> kLegacyAttentionNames[] = {
    {".query.", ".to_q."}, {".key.", ".to_k."}, {".value.", ".to_v."}, {".proj_attn.", ".to_out.0."}};

std::optional<std::string> modern_attention_key(const std::string& key) {
  for (const auto& [legacy, modern] : kLegacyAttentionNames) {
    const size_t pos = key.rfind(legacy);
    if (pos != std::string::npos) return key.substr(0, pos) + modern + key.substr(pos + std::string(legacy).size());
  }
  return std::nullopt;
}

bool is_attention_projection_weight(const std::string& key) {
  for (const char* suffix : {".to_q.weight", ".to_k.weight", ".to_v.weight", ".to_out.0.weight"}) {
    const std::string s(suffix);
    if (key.size() >= s.size() && key.compare(key.size() - s.size(), s.size(), s) == 0) return true;
  }
  return false;
}

bool matches_any(const std::vector<std::string>& patterns, const std::string& key) {
  for (const auto& p : patterns)
    if (key_matches(p, key)) return true;
  return false;
}

std::string shape_string(at::IntArrayRef sizes) {
  std::ostringstream os;
  os << sizes;
  return os.str();
}

// Lists at most 12 entries so a completely wrong checkpoint still gives a readable message.
void append_list(std::ostringstream& os, const std::string& title, const std::vector<std::string>& items) {
  if (items.empty()) return;
  os << "\n  " << title << " (" << items.size() << "):";
  const size_t shown = std::min<size_t>(items.size(), 12);
  for (size_t i = 0; i < shown; ++i) os << "\n    " << items[i];
  if (shown < items.size()) os << "\n    ... and " << items.size() - shown << " more";
}

}  // namespace

LoadPolicy clip_policy() { return LoadPolicy{{}, {"*.embeddings.position_ids"}}; }

bool key_matches(const std::string& pattern, const std::string& key) {
  // Iterative glob with backtracking to the last '*'.
  size_t p = 0, k = 0, star = std::string::npos, resume = 0;
  while (k < key.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = k;
    } else if (p < pattern.size() && pattern[p] == key[k]) {
      ++p;
      ++k;
    } else if (star != std::string::npos) {
      p = star + 1;
      k = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

TensorMap take_prefix(TensorMap& weights, const std::string& prefix) {
  TensorMap taken;
  for (auto it = weights.lower_bound(prefix); it != weights.end() && it->first.compare(0, prefix.size(), prefix) == 0;) {
    taken.emplace(it->first.substr(prefix.size()), std::move(it->second));
    it = weights.erase(it);
  }
  return taken;
}

namespace {

// Which file tensor goes into which module tensor, checked.
struct LoadPlan {
  LoadReport report;
  std::map<std::string, torch::Tensor> targets;                            // module key -> tensor
  std::map<std::string, std::pair<std::string, torch::Tensor>> sources;  // module key -> (file key, tensor)
};

LoadPlan plan_load(torch::nn::Module& module, const TensorMap& weights, const LoadPolicy& policy,
                   const std::string& source) {
  LoadPlan result;
  auto& targets = result.targets;
  auto& report = result.report;
  auto& plan = result.sources;
  for (const auto& item : module.named_parameters(/*recurse=*/true)) targets[item.key()] = item.value();
  for (const auto& item : module.named_buffers(/*recurse=*/true)) targets[item.key()] = item.value();

  std::vector<std::string> unexpected, missing, bad_shape, bad_dtype, duplicate;
  for (const auto& [file_key, tensor] : weights) {
    std::string key = file_key;
    if (!targets.count(key)) {
      auto modern = modern_attention_key(key);
      if (modern && targets.count(*modern)) {
        key = *modern;
        report.renamed.push_back(file_key + " -> " + key);
      }
    }
    if (!targets.count(key)) {
      if (matches_any(policy.may_be_unexpected, file_key)) report.ignored.push_back(file_key);
      else unexpected.push_back(file_key + " " + shape_string(tensor.sizes()));
      continue;
    }
    auto [it, inserted] = plan.emplace(key, std::pair{file_key, tensor});
    if (!inserted) duplicate.push_back(key + " (as " + it->second.first + " and " + file_key + ")");
  }

  for (auto& [key, target] : targets) {
    auto it = plan.find(key);
    if (it == plan.end()) {
      if (matches_any(policy.may_be_missing, key)) report.missing_allowed.push_back(key);
      else missing.push_back(key + " " + shape_string(target.sizes()));
      continue;
    }
    torch::Tensor& src = it->second.second;
    const bool conv_1x1_as_linear = is_attention_projection_weight(key) && src.dim() == 4 && target.dim() == 2 &&
                                    src.size(0) == target.size(0) && src.size(1) == target.size(1) &&
                                    src.size(2) == 1 && src.size(3) == 1;
    if (conv_1x1_as_linear) src = src.reshape(target.sizes());
    if (src.sizes() != target.sizes()) {
      bad_shape.push_back(it->second.first + ": file " + shape_string(src.sizes()) + ", model " +
                          shape_string(target.sizes()));
      continue;
    }
    const bool same_kind = (src.is_floating_point() && target.is_floating_point()) ||
                           (at::isIntegralType(src.scalar_type(), /*includeBool=*/false) &&
                            at::isIntegralType(target.scalar_type(), /*includeBool=*/false)) ||
                           (src.scalar_type() == at::kBool && target.scalar_type() == at::kBool);
    if (!same_kind) {
      bad_dtype.push_back(it->second.first + ": file " + std::string(c10::toString(src.scalar_type())) +
                          ", model " + c10::toString(target.scalar_type()));
    }
  }

  if (!(unexpected.empty() && missing.empty() && bad_shape.empty() && bad_dtype.empty() && duplicate.empty())) {
    std::ostringstream os;
    os << source << ": checkpoint does not match the model";
    append_list(os, "missing tensors", missing);
    append_list(os, "unexpected tensors", unexpected);
    append_list(os, "shape mismatches", bad_shape);
    append_list(os, "wrong dtypes", bad_dtype);
    append_list(os, "tensors given twice", duplicate);
    throw Error(os.str());
  }
  return result;
}

}  // namespace

LoadReport check_state_dict(torch::nn::Module& module, const TensorMap& weights, const LoadPolicy& policy,
                            const std::string& source) {
  return plan_load(module, weights, policy, source).report;
}

LoadReport load_state_dict(torch::nn::Module& module, TensorMap weights, const LoadPolicy& policy,
                           const std::string& source) {
  LoadPlan plan = plan_load(module, weights, policy, source);
  LoadReport& report = plan.report;
  auto& targets = plan.targets;
  torch::NoGradGuard no_grad;
  constexpr size_t kReleaseEveryBytes = size_t(256) << 20;
  size_t freed_bytes = 0;
  for (auto& [key, entry] : plan.sources) {
    torch::Tensor& target = targets.at(key);
    torch::Tensor src = entry.second;
    if (src.scalar_type() != target.scalar_type()) {
      report.converted.push_back(key + ": " + c10::toString(src.scalar_type()) + " -> " +
                                 c10::toString(target.scalar_type()));
    }
    target.copy_(src);
    ++report.loaded;
    entry.second = torch::Tensor();  // the last handle to the file's tensor: its memory goes now
    weights.erase(entry.first);
    // The allocator keeps freed blocks (core/memory.h): hand them back as the load goes, or the file's
    // tensors would stay resident beside the module until the end.
    freed_bytes += src.nbytes();
    if (freed_bytes >= kReleaseEveryBytes) {
      src = torch::Tensor();
      release_freed_memory();
      freed_bytes = 0;
    }
  }
  return report;
}

}  // namespace u3d::nn
