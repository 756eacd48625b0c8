#include "nn/layers/onednn_linear.h"

#include <algorithm>
#include <sys/mman.h>

#include <cstring>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "nn/layers/onednn_common.h"
#include "nn/precision.h"
#include "nn/runtime.h"

namespace u3d::nn {

namespace {

using Tag = dnnl::memory::format_tag;
using DataType = dnnl::memory::data_type;

DataType dnnl_type(const torch::Tensor& t) {
  return t.scalar_type() == torch::kBFloat16 ? DataType::bf16 : DataType::f32;
}

// The row count the weights are packed for when pack_in_place is called, before any input is seen. The
// kernel's layout for the weights does not depend on it here (oneDNN 2.6 on Zen 5, 1 to 8,192 rows); where
// a row count's kernel wants another layout, its plan gets its own copy.
constexpr int64_t kPackingRows = 4096;

bool weights_apply(const torch::Tensor& weight) {
  const torch::ScalarType type = weight.scalar_type();
  return weight.device().is_cpu() && weight.dim() == 2 &&
         ((type == torch::kFloat && cpu_runs_avx512_kernels()) || (type == torch::kBFloat16 && cpu_has_bf16_kernels()));
}

}  // namespace

struct OnednnLinear::State {
  struct Plan {
    int64_t rows;
    bool has_bias, bias_f32;
    Epilogue epilogue;
    dnnl::matmul::primitive_desc pd;
    dnnl::matmul primitive;
    dnnl::memory own_weights;  // the packed weights in this plan's layout where it is not `packed`'s
  };
  mutable std::mutex mutex;
  bool pack_in_place = false;
  WeightKey key;
  std::vector<Plan> plans;
  // The weight tensor's storage holds the layout `packed` (pack_in_place); the plans read it from there.
  bool packed_in_place = false;
  dnnl::memory::desc packed;

  static dnnl::matmul::primitive_desc make(int64_t rows, const torch::Tensor& weight, const dnnl::memory::desc& weights,
                                           const torch::Tensor& bias, Epilogue epilogue = Epilogue::none) {
    const int64_t out = weight.size(0);
    const DataType type = dnnl_type(weight);
    const dnnl::memory::desc src({rows, weight.size(1)}, type, Tag::ab), dst({rows, out}, type, Tag::ab);
    dnnl::primitive_attr attr;
    attr.set_scratchpad_mode(dnnl::scratchpad_mode::user);
    dnnl::post_ops post_ops;
    if (epilogue == Epilogue::gelu) post_ops.append_eltwise(1.0f, dnnl::algorithm::eltwise_gelu_erf, 0.0f, 0.0f);
    if (epilogue == Epilogue::multiply) post_ops.append_binary(dnnl::algorithm::binary_mul, dst);
    attr.set_post_ops(post_ops);
    if (!bias.defined()) return {dnnl::matmul::desc(src, weights, dst), attr, onednn_cpu_engine()};
    const dnnl::memory::desc bias_desc({1, out}, dnnl_type(bias), Tag::ab);
    return {dnnl::matmul::desc(src, weights, bias_desc, dst), attr, onednn_cpu_engine()};
  }
  // The product's right factor is weightᵀ [in, out]: the plain [out, in] rows are its `ba` layout.
  static dnnl::memory::desc plain(const torch::Tensor& weight) {
    return {{weight.size(1), weight.size(0)}, dnnl_type(weight), Tag::ba};
  }
  static dnnl::memory::desc any(const torch::Tensor& weight) {
    return {{weight.size(1), weight.size(0)}, dnnl_type(weight), Tag::any};
  }

  // New values in the weight tensor (a load, set_data, copy_): plain again, and packed where asked.
  void refresh(const torch::Tensor& weight) {
    const WeightKey current = weight_key(weight);
    if (current == key) return;
    plans.clear();
    packed_in_place = false;
    key = current;
    if (pack_in_place) pack(weight);
  }

  // The plain weights reordered into the kernel's layout in their own storage, where that layout fits in
  // their bytes, through a buffer (a reorder cannot write over its source) mapped for the purpose and
  // returned to the system at once: from libtorch's allocator or the heap, the buffers of a UNet's
  // layers stayed resident (the normal step's peak RSS 0.15 GB higher).
  void pack(const torch::Tensor& weight) {
    if (!weight.is_contiguous()) return;
    const dnnl::memory::desc desc = make(kPackingRows, weight, any(weight), {}).weights_desc();
    const size_t bytes = desc.get_size();
    if (bytes > weight.nbytes()) return;
    void* buffer = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    TORCH_CHECK(buffer != MAP_FAILED, "linear: no memory for packing ", bytes, " bytes of weights");
    dnnl::memory source(plain(weight), onednn_cpu_engine(), weight.data_ptr());
    dnnl::memory target(desc, onednn_cpu_engine(), buffer);
    onednn_reorder(source, target);
    std::memcpy(weight.data_ptr(), buffer, bytes);
    munmap(buffer, bytes);
    packed_in_place = true;
    packed = desc;
  }

  const Plan& plan_for(int64_t rows, const torch::Tensor& weight, const torch::Tensor& bias, Epilogue epilogue) {
    refresh(weight);
    const bool has_bias = bias.defined(), bias_f32 = has_bias && bias.scalar_type() == torch::kFloat;
    for (const Plan& p : plans)
      if (p.rows == rows && p.has_bias == has_bias && p.bias_f32 == bias_f32 && p.epilogue == epilogue) return p;
    if (!packed_in_place) {
      const auto pd = make(rows, weight, plain(weight), bias, epilogue);
      plans.push_back({rows, has_bias, bias_f32, epilogue, pd, dnnl::matmul(pd), {}});
      return plans.back();
    }
    const auto pd = make(rows, weight, any(weight), bias, epilogue);
    dnnl::memory own;
    if (pd.weights_desc() != packed) {
      dnnl::memory source(packed, onednn_cpu_engine(), weight.data_ptr());
      own = dnnl::memory(pd.weights_desc(), onednn_cpu_engine());
      onednn_reorder(source, own);
    }
    plans.push_back({rows, has_bias, bias_f32, epilogue, pd, dnnl::matmul(pd), own});
    return plans.back();
  }
};

bool OnednnLinear::applies(const torch::Tensor& x, const torch::Tensor& weight) {
  return x.device().is_cpu() && x.dim() >= 1 && weight.scalar_type() == x.scalar_type() && weights_apply(weight);
}

OnednnLinear::OnednnLinear() : state_(std::make_unique<State>()) {}
OnednnLinear::~OnednnLinear() = default;

void OnednnLinear::pack_in_place(const torch::Tensor& weight) {
  if (!weights_apply(weight)) return;
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->pack_in_place = true;
  state_->key = {};
  state_->refresh(weight);
}

bool OnednnLinear::holds_packed_weights() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->packed_in_place;
}

torch::Tensor OnednnLinear::forward(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias,
                                   Epilogue epilogue, const torch::Tensor& factor) {
  const int64_t in = weight.size(1), out_features = weight.size(0);
  TORCH_CHECK(x.size(-1) == in, "linear: input has ", x.size(-1), " features, the weights expect ", in);
  TORCH_CHECK(!bias.defined() || ((bias.scalar_type() == weight.scalar_type() || bias.scalar_type() == torch::kFloat) &&
                                  bias.numel() == out_features),
              "linear: the bias must have the weights' dtype or fp32, with one value per output");
  std::vector<int64_t> sizes = x.sizes().vec();
  sizes.back() = out_features;
  TORCH_CHECK(epilogue != Epilogue::multiply || (factor.defined() && factor.sizes() == torch::IntArrayRef(sizes) &&
                                                 factor.scalar_type() == x.scalar_type() && factor.is_contiguous()),
              "linear: the factor must be a contiguous tensor of the output's shape and dtype");
  const int64_t rows = x.numel() / std::max<int64_t>(in, 1);
  if (rows == 0 || out_features == 0) return torch::empty(sizes, x.options());
  if (in == 0) {
    torch::Tensor out = bias.defined() ? bias.to(x.scalar_type()).expand(sizes).contiguous() : torch::zeros(sizes, x.options());
    if (epilogue == Epilogue::gelu) return torch::gelu(out);
    return epilogue == Epilogue::multiply ? out * factor : out;
  }
  const torch::Tensor a = x.contiguous();
  const torch::Tensor bias_c = bias.defined() ? bias.contiguous() : bias;
  torch::Tensor out = torch::empty(sizes, x.options());
  std::lock_guard<std::mutex> lock(state_->mutex);
  const State::Plan& plan = state_->plan_for(rows, weight, bias_c, epilogue);
  const auto& pd = plan.pd;
  const torch::Tensor w = state_->packed_in_place ? weight : weight.contiguous();
  std::unordered_map<int, dnnl::memory> args{
      {DNNL_ARG_SRC, dnnl::memory(pd.src_desc(), onednn_cpu_engine(), a.data_ptr())},
      {DNNL_ARG_WEIGHTS, plan.own_weights ? plan.own_weights
                                          : dnnl::memory(pd.weights_desc(), onednn_cpu_engine(), w.data_ptr())},
      {DNNL_ARG_DST, dnnl::memory(pd.dst_desc(), onednn_cpu_engine(), out.data_ptr())}};
  if (bias_c.defined())
    args.emplace(DNNL_ARG_BIAS, dnnl::memory(pd.bias_desc(), onednn_cpu_engine(), bias_c.data_ptr()));
  if (epilogue == Epilogue::multiply)
    args.emplace(DNNL_ARG_ATTR_MULTIPLE_POST_OP(0) | DNNL_ARG_SRC_1,
                 dnnl::memory(pd.dst_desc(), onednn_cpu_engine(), factor.data_ptr()));
  onednn_execute(plan.primitive, pd.scratchpad_desc(), std::move(args));
  return out;
}

}  // namespace u3d::nn
