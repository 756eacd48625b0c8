#include "nn/models/rrdbnet_cpu.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <mutex>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nn/layers/onednn_common.h"
#include "nn/models/rrdbnet.h"
#include "nn/precision.h"

namespace u3d::nn {
namespace {

using Desc = dnnl::memory::desc;
using Tag = dnnl::memory::format_tag;
using DataType = dnnl::memory::data_type;
using ConvPd = dnnl::convolution_forward::primitive_desc;

constexpr float kSlope = 0.2f;          // LeakyReLU negative slope (nn/models/rrdbnet.cpp)
constexpr float kResidualScale = 0.2f;  // each dense block and RRDB adds 0.2 x its output
constexpr int64_t kUp = 2;              // each upsampling step is nearest x2

// The channel block of the layout oneDNN's direct kernels read and write on this CPU.
int64_t channel_block() {
  const int isa = static_cast<int>(dnnl::get_effective_cpu_isa());
  return (isa & dnnl_cpu_isa_avx512_core) == dnnl_cpu_isa_avx512_core ? 16 : 8;
}

int64_t round_up(int64_t value, int64_t block) { return (value + block - 1) / block * block; }

DataType dnnl_type(torch::ScalarType type) { return type == torch::kBFloat16 ? DataType::bf16 : DataType::f32; }

// The roles a convolution plays; layers with the same role share a kernel (their shapes and post-ops
// are equal), each with its own packed weights.
enum Role : size_t {
  kFirst,       // conv_first: the input (plain NCHW) -> feat
  kDense1,      // conv1..conv4 of a dense block: LeakyReLU, written after their input in the block buffer
  kDense5 = 5,  // conv5 of rdb1 and rdb2: 0.2 x + the block's input
  kDense5Last,  // conv5 of rdb3: 0.2 (0.2 x + the block's input) + the RRDB's input
  kBody,        // conv_body: + feat
  kUp1,         // conv_up1 at 2H x 2W: LeakyReLU
  kUp2,         // conv_up2 at 4H x 4W: LeakyReLU
  kHr,          // conv_hr at 4H x 4W: LeakyReLU
  kLast,        // conv_last at 4H x 4W -> the output (plain NCHW)
  kRoles
};

// `count` real input channels that start at `real` in the weights and at `padded` in the layout.
struct Group {
  int64_t real, padded, count;
};

struct Layer {
  const Conv2dImpl* conv = nullptr;
  Role role = kFirst;
  std::vector<Group> inputs;
  int64_t in_padded = 0, out_padded = 0;
  torch::Tensor bias;                                 // padded to out_padded
  std::vector<std::pair<Desc, dnnl::memory>> packed;  // the weights in each layout a kernel asked for

  // The weights [out, in, kh, kw] spread over the padded channels; the padding's weights are 0.
  torch::Tensor padded_weights() const {
    const torch::Tensor& w = conv->weight;
    if (in_padded == w.size(1) && out_padded == w.size(0)) return w.contiguous();
    torch::Tensor p = torch::zeros({out_padded, in_padded, w.size(2), w.size(3)}, w.options());
    for (const Group& g : inputs)
      p.slice(0, 0, w.size(0)).slice(1, g.padded, g.padded + g.count).copy_(w.slice(1, g.real, g.real + g.count));
    return p;
  }

  const dnnl::memory& weights_for(const Desc& desc) {
    for (const auto& [d, memory] : packed)
      if (d == desc) return memory;
    const torch::Tensor plain = padded_weights();
    const torch::Tensor& w = conv->weight;
    dnnl::memory source({{plain.size(0), plain.size(1), w.size(2), w.size(3)}, dnnl_type(w.scalar_type()), Tag::oihw},
                        onednn_cpu_engine(), plain.data_ptr());
    dnnl::memory target(desc, onednn_cpu_engine());
    onednn_reorder(source, target);
    packed.emplace_back(desc, target);
    return packed.back().second;
  }
};

}  // namespace

struct RrdbCpuForward::State {
  struct Plan {
    int64_t h = 0, w = 0;
    DataType out_type = DataType::f32;
    std::array<ConvPd, kRoles> pds;
    std::array<dnnl::convolution_forward, kRoles> convs;
    dnnl::resampling_forward up_small, up_large;  // H -> 2H, 2H -> 4H
    dnnl::reorder to_plain;                       // the output, blocked -> NCHW
    size_t scratch = 0;
  };

  std::mutex mutex;
  std::vector<WeightKey> key;
  std::vector<Layer> layers;
  int64_t block = 0, in = 0, out = 0, feat = 0, grow = 0;  // feat, grow: padded
  DataType type = DataType::f32;
  std::vector<Plan> plans;
  bool keep_workspace = false;
  torch::Tensor workspace;  // kept while keep_workspace

  Tag blocked() const { return block == 16 ? Tag::nChw16c : Tag::nChw8c; }
  int64_t buffer_channels() const { return feat + 4 * grow; }

  // The layers of `net` in the order forward runs them; rebuilt (and the plans dropped) when a weight
  // changed.
  void update(const RRDBNetImpl& net) {
    std::vector<const Conv2dImpl*> convs{net.conv_first.get()};
    for (const RRDB& b : net.body)
      for (const ResidualDenseBlock& r : {b->rdb1, b->rdb2, b->rdb3})
        for (const Conv2d& c : {r->conv1, r->conv2, r->conv3, r->conv4, r->conv5}) convs.push_back(c.get());
    for (const Conv2d& c : {net.conv_body, net.conv_up1, net.conv_up2, net.conv_hr, net.conv_last})
      convs.push_back(c.get());
    std::vector<WeightKey> current;
    for (const Conv2dImpl* c : convs) {
      current.push_back(weight_key(c->weight));
      current.push_back(weight_key(c->bias));
    }
    if (current == key) return;
    key = std::move(current);
    plans.clear();
    layers.clear();
    block = channel_block();
    type = dnnl_type(net.conv_first->weight.scalar_type());
    in = net.config.in_channels;
    out = net.config.out_channels;
    const int64_t f = net.config.num_feat, g = net.config.num_grow;
    feat = round_up(f, block);
    grow = round_up(g, block);
    auto add = [&](const Conv2dImpl* conv, Role role, std::vector<Group> inputs, int64_t in_padded,
                   int64_t out_padded) {
      Layer layer{conv, role, std::move(inputs), in_padded, out_padded, {}, {}};
      layer.bias = torch::zeros({out_padded}, conv->bias.options());
      layer.bias.slice(0, 0, conv->bias.size(0)).copy_(conv->bias);
      layers.push_back(std::move(layer));
    };
    size_t next = 0;
    add(convs[next++], kFirst, {{0, 0, in}}, in, feat);
    for (size_t b = 0; b < net.body.size(); ++b)
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 5; ++k) {
          std::vector<Group> inputs{{0, 0, f}};
          for (int j = 0; j < k; ++j) inputs.push_back({f + j * g, feat + j * grow, g});
          const Role role = k < 4 ? Role(kDense1 + k) : r < 2 ? kDense5 : kDense5Last;
          add(convs[next++], role, std::move(inputs), feat + k * grow, k < 4 ? grow : feat);
        }
    add(convs[next++], kBody, {{0, 0, f}}, feat, feat);
    add(convs[next++], kUp1, {{0, 0, f}}, feat, feat);
    add(convs[next++], kUp2, {{0, 0, f}}, feat, feat);
    add(convs[next++], kHr, {{0, 0, f}}, feat, feat);
    add(convs[next++], kLast, {{0, 0, f}}, feat, out);
  }

  Desc activations(int64_t channels, int64_t h, int64_t w) const { return Desc({1, channels, h, w}, type, blocked()); }

  ConvPd make_conv(const Desc& src, const Desc& dst, const Layer& like, const dnnl::post_ops& ops) const {
    const torch::Tensor& weight = like.conv->weight;
    const dnnl::memory::dim pad = like.conv->padding, stride = like.conv->stride;
    const Desc weights({like.out_padded, like.in_padded, weight.size(2), weight.size(3)}, type, Tag::any);
    const Desc bias({like.out_padded}, dnnl_type(like.bias.scalar_type()), Tag::a);
    const dnnl::convolution_forward::desc desc(dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct,
                                               src, weights, bias, dst, {stride, stride}, {pad, pad}, {pad, pad});
    dnnl::primitive_attr attr;
    attr.set_post_ops(ops);
    attr.set_scratchpad_mode(dnnl::scratchpad_mode::user);
    return ConvPd(desc, attr, onednn_cpu_engine());
  }

  const Plan& plan_for(int64_t h, int64_t w, DataType out_type) {
    for (const Plan& p : plans)
      if (p.h == h && p.w == w && p.out_type == out_type) return p;
    Plan p;
    p.h = h;
    p.w = w;
    p.out_type = out_type;
    const int64_t h2 = kUp * h, w2 = kUp * w, h4 = kUp * h2, w4 = kUp * w2;
    std::array<const Layer*, kRoles> like{};
    for (const Layer& layer : layers)
      if (!like[layer.role]) like[layer.role] = &layer;
    dnnl::post_ops lrelu;
    lrelu.append_eltwise(1.f, dnnl::algorithm::eltwise_relu, kSlope, 0.f);
    const Desc feat_desc = activations(feat, h, w);
    // 0.2 x + the block's input, `times` times (a copy of a post_ops is the same chain, so each is new).
    auto residual = [&](int times) {
      dnnl::post_ops ops;
      for (int i = 0; i < times; ++i) {
        ops.append_eltwise(1.f, dnnl::algorithm::eltwise_linear, kResidualScale, 0.f);
        ops.append_binary(dnnl::algorithm::binary_add, feat_desc);
      }
      return ops;
    };
    dnnl::post_ops skip;
    skip.append_binary(dnnl::algorithm::binary_add, feat_desc);

    p.pds[kFirst] = make_conv(Desc({1, in, h, w}, type, Tag::nchw), feat_desc, *like[kFirst], {});
    for (int k = 0; k < 4; ++k)
      p.pds[kDense1 + k] =
          make_conv(activations(feat + k * grow, h, w), activations(grow, h, w), *like[kDense1 + k], lrelu);
    p.pds[kDense5] = make_conv(activations(buffer_channels(), h, w), feat_desc, *like[kDense5], residual(1));
    p.pds[kDense5Last] = make_conv(activations(buffer_channels(), h, w), feat_desc, *like[kDense5Last], residual(2));
    p.pds[kBody] = make_conv(feat_desc, feat_desc, *like[kBody], skip);
    p.pds[kUp1] = make_conv(activations(feat, h2, w2), activations(feat, h2, w2), *like[kUp1], lrelu);
    p.pds[kUp2] = make_conv(activations(feat, h4, w4), activations(feat, h4, w4), *like[kUp2], lrelu);
    p.pds[kHr] = make_conv(activations(feat, h4, w4), activations(feat, h4, w4), *like[kHr], lrelu);
    // The output in the blocked layout (its channels padded to the block there: oneDNN's direct kernels
    // write no plain layout), then reordered to plain NCHW.
    const Desc out_blocked({1, out, h4, w4}, out_type, blocked());
    p.pds[kLast] = make_conv(activations(feat, h4, w4), out_blocked, *like[kLast], {});
    p.to_plain =
        dnnl::reorder(dnnl::memory(out_blocked, onednn_cpu_engine(), DNNL_MEMORY_NONE),
                      dnnl::memory(Desc({1, out, h4, w4}, out_type, Tag::nchw), onednn_cpu_engine(), DNNL_MEMORY_NONE));
    for (size_t r = 0; r < kRoles; ++r) {
      p.convs[r] = dnnl::convolution_forward(p.pds[r]);
      p.scratch = std::max(p.scratch, p.pds[r].scratchpad_desc().get_size());
    }
    dnnl::primitive_attr attr;
    attr.set_scratchpad_mode(dnnl::scratchpad_mode::user);
    auto resample = [&](const Desc& src, const Desc& dst) {
      const dnnl::resampling_forward::primitive_desc pd(
          dnnl::resampling_forward::desc(dnnl::prop_kind::forward_inference, dnnl::algorithm::resampling_nearest, src,
                                         dst),
          attr, onednn_cpu_engine());
      p.scratch = std::max(p.scratch, pd.scratchpad_desc().get_size());
      return dnnl::resampling_forward(pd);
    };
    p.up_small = resample(feat_desc, activations(feat, h2, w2));
    p.up_large = resample(activations(feat, h2, w2), activations(feat, h4, w4));
    plans.push_back(std::move(p));
    return plans.back();
  }
};

bool RrdbCpuForward::applies(const torch::Tensor& x, const torch::Tensor& weight) {
  const bool input_ok =
      x.device().is_cpu() && x.dim() == 4 && (x.scalar_type() == torch::kFloat || x.scalar_type() == torch::kBFloat16);
  const bool weights_ok =
      weight.device().is_cpu() &&
      (weight.scalar_type() == torch::kFloat || (weight.scalar_type() == torch::kBFloat16 && cpu_has_bf16_kernels()));
  return input_ok && weights_ok;
}

RrdbCpuForward::RrdbCpuForward() : state_(std::make_unique<State>()) {}
RrdbCpuForward::~RrdbCpuForward() = default;

void RrdbCpuForward::keep_workspace(bool keep) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->keep_workspace = keep;
  if (!keep) state_->workspace = torch::Tensor();
}

torch::Tensor RrdbCpuForward::forward(const RRDBNetImpl& net, const torch::Tensor& x) {
  TORCH_CHECK(x.size(1) == net.config.in_channels, "RRDBNet: input has ", x.size(1), " channels, the network expects ",
              net.config.in_channels);
  std::lock_guard<std::mutex> lock(state_->mutex);
  State& s = *state_;
  s.update(net);
  const torch::ScalarType weight_type = net.conv_first->weight.scalar_type();
  const torch::Tensor input = x.to(weight_type).contiguous();
  const int64_t n = x.size(0), h = x.size(2), w = x.size(3);
  // A bf16 network returns fp32 directly where the caller wants fp32 (its last convolution accumulates
  // in fp32 anyway); otherwise the output is in the weights' type.
  const torch::ScalarType out_type = x.scalar_type() == torch::kFloat ? torch::kFloat : weight_type;
  const State::Plan& plan = s.plan_for(h, w, dnnl_type(out_type));
  const int64_t h4 = kUp * kUp * h, w4 = kUp * kUp * w;
  torch::Tensor result = torch::empty({n, s.out, h4, w4}, x.options().dtype(out_type));

  // Every buffer is a part of one workspace: kept between calls while keep_workspace is on (the tiles of
  // an image are the same size), else from libtorch's allocator for this call.
  const int64_t element = static_cast<int64_t>(input.element_size());
  size_t total = 0;
  auto part = [&](size_t count) {
    const size_t offset = total;
    total += (count + 63) / 64 * 64;
    return offset;
  };
  auto activation = [&](int64_t channels, int64_t pixels) { return part(size_t(channels * pixels * element)); };
  const std::array<size_t, 3> block_at{activation(s.buffer_channels(), h * w), activation(s.buffer_channels(), h * w),
                                       activation(s.buffer_channels(), h * w)};
  const size_t feat_at = activation(s.feat, h * w);
  const size_t up2a_at = activation(s.feat, 4 * h * w), up2b_at = activation(s.feat, 4 * h * w);
  const size_t up4a_at = activation(s.feat, 16 * h * w), up4b_at = activation(s.feat, 16 * h * w);
  const size_t out_at = part(plan.pds[kLast].dst_desc().get_size());
  const size_t scratch_at = part(plan.scratch);
  torch::Tensor workspace = s.workspace;
  if (!workspace.defined() || size_t(workspace.numel()) < total)
    workspace = torch::empty({static_cast<int64_t>(total)}, torch::TensorOptions().dtype(torch::kUInt8));
  if (s.keep_workspace) s.workspace = workspace;
  uint8_t* const base = workspace.data_ptr<uint8_t>();
  const std::array<uint8_t*, 3> blocks{base + block_at[0], base + block_at[1], base + block_at[2]};
  uint8_t *const feat = base + feat_at, *const up2a = base + up2a_at, *const up2b = base + up2b_at,
                 *const up4a = base + up4a_at, *const up4b = base + up4b_at, *const blocked_out = base + out_at;

  dnnl::stream stream(onednn_cpu_engine());
  const dnnl::memory scratch_memory({{static_cast<dnnl::memory::dim>(plan.scratch)}, DataType::u8, Tag::a},
                                    onednn_cpu_engine(), base + scratch_at);
  // Channel c of an image starts at c x H x W elements in the blocked layout (N = 1, c a multiple of the
  // block).
  auto at_channel = [&](uint8_t* buffer, int64_t channel, int64_t pixels) {
    return buffer + channel * pixels * element;
  };
  auto run = [&](Layer& layer, void* src, void* dst, std::vector<void*> addends = {}) {
    const ConvPd& pd = plan.pds[layer.role];
    std::unordered_map<int, dnnl::memory> args{
        {DNNL_ARG_SRC, dnnl::memory(pd.src_desc(), onednn_cpu_engine(), src)},
        {DNNL_ARG_WEIGHTS, layer.weights_for(pd.weights_desc())},
        {DNNL_ARG_BIAS, dnnl::memory(pd.bias_desc(), onednn_cpu_engine(), layer.bias.data_ptr())},
        {DNNL_ARG_DST, dnnl::memory(pd.dst_desc(), onednn_cpu_engine(), dst)},
        {DNNL_ARG_SCRATCHPAD, scratch_memory}};
    // The binary post-ops are the 2nd and 4th of their chains (after a scaling) or the only one.
    const std::array<int, 2> index = layer.role == kBody ? std::array<int, 2>{0, 0} : std::array<int, 2>{1, 3};
    for (size_t i = 0; i < addends.size(); ++i)
      args.emplace(DNNL_ARG_ATTR_MULTIPLE_POST_OP(index[i]) | DNNL_ARG_SRC_1,
                   dnnl::memory(s.activations(s.feat, plan.h, plan.w), onednn_cpu_engine(), addends[i]));
    plan.convs[layer.role].execute(stream, args);
  };
  auto upsample = [&](const dnnl::resampling_forward& primitive, const Desc& src_desc, const Desc& dst_desc, void* src,
                      void* dst) {
    primitive.execute(stream, {{DNNL_ARG_SRC, dnnl::memory(src_desc, onednn_cpu_engine(), src)},
                               {DNNL_ARG_DST, dnnl::memory(dst_desc, onednn_cpu_engine(), dst)},
                               {DNNL_ARG_SCRATCHPAD, scratch_memory}});
  };

  const int64_t pixels = h * w;
  for (int64_t i = 0; i < n; ++i) {
    size_t next = 0;
    run(s.layers[next++], input[i].data_ptr(), feat);
    std::memcpy(blocks[0], feat, static_cast<size_t>(s.feat * pixels * element));
    // The RRDB's input is in blocks[a]'s first channels; its dense blocks go a -> b -> c -> b.
    size_t a = 0, b = 1, c = 2;
    auto dense_block = [&](uint8_t* buf, void* dst, std::vector<void*> addends) {
      for (int k = 0; k < 4; ++k) run(s.layers[next++], buf, at_channel(buf, s.feat + k * s.grow, pixels));
      run(s.layers[next++], buf, dst, std::move(addends));
    };
    for (size_t block = 0; block < net.body.size(); ++block) {
      dense_block(blocks[a], blocks[b], {blocks[a]});
      dense_block(blocks[b], blocks[c], {blocks[b]});
      dense_block(blocks[c], blocks[b], {blocks[c], blocks[a]});
      std::swap(a, b);
    }
    run(s.layers[next++], blocks[a], blocks[b], {feat});
    const Desc feat1 = s.activations(s.feat, h, w), feat2 = s.activations(s.feat, 2 * h, 2 * w),
               feat4 = s.activations(s.feat, h4, w4);
    upsample(plan.up_small, feat1, feat2, blocks[b], up2a);
    run(s.layers[next++], up2a, up2b);
    upsample(plan.up_large, feat2, feat4, up2b, up4a);
    run(s.layers[next++], up4a, up4b);
    run(s.layers[next++], up4b, up4a);
    run(s.layers[next++], up4a, blocked_out);
    const ConvPd& last = plan.pds[kLast];
    dnnl::memory last_out(last.dst_desc(), onednn_cpu_engine(), blocked_out);
    dnnl::memory plain_out(Desc({1, s.out, h4, w4}, last.dst_desc().data_type(), Tag::nchw), onednn_cpu_engine(),
                           result[i].data_ptr());
    plan.to_plain.execute(stream, last_out, plain_out);
  }
  stream.wait();
  return x.scalar_type() == out_type ? result : result.to(x.scalar_type());
}

}  // namespace u3d::nn
