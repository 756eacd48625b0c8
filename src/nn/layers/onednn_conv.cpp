#include "nn/layers/onednn_conv.h"

#include "nn/layers/onednn_common.h"
#include "nn/precision.h"

#include <array>
#include <cstring>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

namespace u3d::nn {

namespace {

using Dims = dnnl::memory::dims;
using Tag = dnnl::memory::format_tag;
using DataType = dnnl::memory::data_type;

// Output sizes (height x width) up to which the direct kernel is taken over oneDNN's first choice.
constexpr int64_t kSmallOutput = 16;

DataType dnnl_type(const torch::Tensor& t) {
  return t.scalar_type() == torch::kBFloat16 ? DataType::bf16 : DataType::f32;
}

}  // namespace

struct OnednnConv2d::State {
  struct Plan {
    std::array<int64_t, 3> input;  // batch, height, width
    dnnl::convolution_forward::primitive_desc pd;
    dnnl::convolution_forward primitive;
    size_t packed;  // index into `packed`
    Dims output;
  };
  struct Packed {
    dnnl::memory::desc desc;
    dnnl::memory weights;
  };
  std::mutex mutex;
  bool pack_in_place = false;
  WeightKey key;
  std::vector<Plan> plans;
  std::vector<Packed> packed;
  // packed[0] is the weight tensor's own storage, in packed[0].desc's layout (pack_in_place).
  bool packed_in_place = false;

  const Plan& plan_for(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias, int64_t stride,
                       int64_t padding) {
    const WeightKey current = weight_key(weight);
    if (!(current == key)) {
      plans.clear();
      packed.clear();
      packed_in_place = false;
      key = current;
    }
    const std::array<int64_t, 3> input{x.size(0), x.size(2), x.size(3)};
    for (const Plan& p : plans)
      if (p.input == input) return p;

    const int64_t kernel_h = weight.size(2), kernel_w = weight.size(3);
    const Dims src_dims{x.size(0), x.size(1), x.size(2), x.size(3)};
    const Dims weight_dims{weight.size(0), weight.size(1), kernel_h, kernel_w};
    const Dims output{x.size(0), weight.size(0), (x.size(2) + 2 * padding - kernel_h) / stride + 1,
                      (x.size(3) + 2 * padding - kernel_w) / stride + 1};
    const DataType type = dnnl_type(weight);
    const dnnl::memory::desc src(src_dims, type, Tag::nhwc);
    const dnnl::memory::desc dst(output, type, Tag::nhwc);
    const dnnl::memory::desc weights_any(weight_dims, type, Tag::any);
    const Dims strides{stride, stride}, pad{padding, padding};
    const auto descriptor =
        bias.defined()
            ? dnnl::convolution_forward::desc(
                  dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct, src, weights_any,
                  dnnl::memory::desc({weight.size(0)}, type, Tag::a), dst, strides, pad, pad)
            : dnnl::convolution_forward::desc(dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct,
                                              src, weights_any, dst, strides, pad, pad);
    dnnl::primitive_attr attr;
    attr.set_scratchpad_mode(dnnl::scratchpad_mode::user);
    dnnl::convolution_forward::primitive_desc pd(descriptor, attr, onednn_cpu_engine());
    if (output[2] * output[3] <= kSmallOutput && std::string(pd.impl_info_str()).find("amx") == std::string::npos) {
      // oneDNN's first choice (brgconv) is slower there than its older direct kernel (bf16, 1,280 channels
      // at 4x4, batch 8: 7.0 against 5.1 ms; fp32 about twice as slow), except where it runs on AMX tiles,
      // which the direct kernel does not use (Intel Xeon since Sapphire Rapids: the 4x4 convolutions of
      // a bf16 UNet forward, batch 8, at 203 GFLOP/s against 138). next_impl() moves the descriptor
      // itself along the list, so without that kernel the list is walked again from its start.
      const char* direct = type == DataType::bf16 ? "jit_bf16:" : "jit:";
      bool found = false;
      do found = std::string(pd.impl_info_str()).starts_with(direct);
      while (!found && pd.next_impl());
      if (!found) pd = dnnl::convolution_forward::primitive_desc(descriptor, attr, onednn_cpu_engine());
    }
    size_t index = 0;
    while (index < packed.size() && packed[index].desc != pd.weights_desc()) ++index;
    if (index == packed.size()) packed.push_back(pack(weight, pd.weights_desc()));
    plans.push_back({input, pd, dnnl::convolution_forward(pd), index, output});
    return plans.back();
  }

  // The weights in `desc`'s layout: in the weight tensor's own storage the first time where pack_in_place
  // asks for it and the layout fits, else a new copy (reordered from the packed storage once the plain
  // values are gone).
  Packed pack(const torch::Tensor& weight, const dnnl::memory::desc& desc) {
    const torch::Tensor plain = packed_in_place ? torch::Tensor() : weight.contiguous();
    dnnl::memory source =
        packed_in_place ? packed.front().weights
                        : dnnl::memory({{weight.size(0), weight.size(1), weight.size(2), weight.size(3)},
                                        dnnl_type(weight), Tag::oihw},
                                       onednn_cpu_engine(), plain.data_ptr());
    const bool in_place =
        pack_in_place && packed.empty() && weight.is_contiguous() && desc.get_size() <= weight.nbytes();
    // In place: through a buffer from libtorch's allocator (a reorder cannot write over its source).
    torch::Tensor buffer;
    dnnl::memory target = in_place ? dnnl::memory(desc, onednn_cpu_engine(),
                                                  (buffer = torch::empty({int64_t(desc.get_size())}, torch::kUInt8))
                                                      .data_ptr())
                                   : dnnl::memory(desc, onednn_cpu_engine());
    onednn_reorder(source, target);
    if (!in_place) return {desc, target};
    std::memcpy(weight.data_ptr(), buffer.data_ptr(), desc.get_size());
    packed_in_place = true;
    return {desc, dnnl::memory(desc, onednn_cpu_engine(), weight.data_ptr())};
  }
};

bool OnednnConv2d::applies(const torch::Tensor& x, const torch::Tensor& weight) {
  const torch::ScalarType type = x.scalar_type();
  return x.device().is_cpu() && weight.device().is_cpu() && x.dim() == 4 && weight.scalar_type() == type &&
         (type == torch::kFloat || (type == torch::kBFloat16 && cpu_has_bf16_kernels()));
}

OnednnConv2d::OnednnConv2d() : state_(std::make_unique<State>()) {}
OnednnConv2d::~OnednnConv2d() = default;

void OnednnConv2d::pack_in_place() {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->pack_in_place = true;
}

torch::Tensor OnednnConv2d::forward(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias,
                                    int64_t stride, int64_t padding) {
  TORCH_CHECK(x.size(1) == weight.size(1), "conv2d: input has ", x.size(1), " channels, the weights expect ",
              weight.size(1));
  TORCH_CHECK(!bias.defined() || bias.scalar_type() == weight.scalar_type(),
              "conv2d: the bias must have the weights' dtype");
  const torch::Tensor input = x.contiguous(at::MemoryFormat::ChannelsLast);
  std::lock_guard<std::mutex> lock(state_->mutex);
  const State::Plan& plan = state_->plan_for(input, weight, bias, stride, padding);
  const Dims& o = plan.output;
  torch::Tensor out = torch::empty({o[0], o[1], o[2], o[3]}, x.options().memory_format(at::MemoryFormat::ChannelsLast));
  const auto& pd = plan.pd;
  dnnl::memory src(pd.src_desc(), onednn_cpu_engine(), input.data_ptr());
  dnnl::memory dst(pd.dst_desc(), onednn_cpu_engine(), out.data_ptr());
  const dnnl::memory& weights = state_->packed[plan.packed].weights;
  std::unordered_map<int, dnnl::memory> args{{DNNL_ARG_SRC, src}, {DNNL_ARG_WEIGHTS, weights}, {DNNL_ARG_DST, dst}};
  const torch::Tensor bias_c = bias.defined() ? bias.contiguous() : bias;
  if (bias_c.defined())
    args.emplace(DNNL_ARG_BIAS, dnnl::memory(pd.bias_desc(), onednn_cpu_engine(), bias_c.data_ptr()));
  onednn_execute(plan.primitive, pd.scratchpad_desc(), std::move(args));
  return out;
}

}  // namespace u3d::nn
