#include "nn/models/rrdbnet.h"

#include "core/error.h"
#include "nn/checkpoint/onnx_weights.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/checkpoint/weights_file.h"

namespace u3d::nn {
namespace {

constexpr double kSlope = 0.2;          // LeakyReLU negative slope
constexpr double kResidualScale = 0.2;  // residual scaling of every dense block and RRDB
constexpr int64_t kConvsPerBlock = 15;  // 3 dense blocks of 5 convs
constexpr int64_t kConvsOutsideBody = 6;

torch::Tensor lrelu(const torch::Tensor& x) { return torch::leaky_relu(x, kSlope); }

const torch::Tensor& weight_of(const TensorMap& weights, const std::string& key, const std::string& source) {
  auto it = weights.find(key);
  require(it != weights.end(), source + ": no tensor '" + key + "' (not an RRDBNet checkpoint?)");
  require(it->second.dim() == 4, source + ": tensor '" + key + "' has " + std::to_string(it->second.dim()) +
                                     " dimensions, an RRDBNet conv weight has 4");
  return it->second;
}

}  // namespace

RRDBNetConfig RRDBNetConfig::from_weights(const TensorMap& weights, const std::string& source) {
  RRDBNetConfig c;
  const torch::Tensor& first = weight_of(weights, "conv_first.weight", source);
  c.in_channels = first.size(1);
  c.num_feat = first.size(0);
  c.out_channels = weight_of(weights, "conv_last.weight", source).size(0);
  c.num_grow = weight_of(weights, "body.0.rdb1.conv1.weight", source).size(0);
  c.num_block = 0;
  while (weights.count("body." + std::to_string(c.num_block) + ".rdb1.conv1.weight")) ++c.num_block;
  return c;
}

ResidualDenseBlockImpl::ResidualDenseBlockImpl(int64_t f, int64_t g, const torch::TensorOptions& o) {
  conv1 = register_module("conv1", Conv2d(f, g, 3, 1, 1, true, o));
  conv2 = register_module("conv2", Conv2d(f + g, g, 3, 1, 1, true, o));
  conv3 = register_module("conv3", Conv2d(f + 2 * g, g, 3, 1, 1, true, o));
  conv4 = register_module("conv4", Conv2d(f + 3 * g, g, 3, 1, 1, true, o));
  conv5 = register_module("conv5", Conv2d(f + 4 * g, f, 3, 1, 1, true, o));
}

torch::Tensor ResidualDenseBlockImpl::forward(const torch::Tensor& x) {
  const torch::Tensor x1 = lrelu(conv1(x));
  const torch::Tensor x2 = lrelu(conv2(torch::cat({x, x1}, 1)));
  const torch::Tensor x3 = lrelu(conv3(torch::cat({x, x1, x2}, 1)));
  const torch::Tensor x4 = lrelu(conv4(torch::cat({x, x1, x2, x3}, 1)));
  const torch::Tensor x5 = conv5(torch::cat({x, x1, x2, x3, x4}, 1));
  return x5 * kResidualScale + x;
}

RRDBImpl::RRDBImpl(int64_t f, int64_t g, const torch::TensorOptions& o) {
  rdb1 = register_module("rdb1", ResidualDenseBlock(f, g, o));
  rdb2 = register_module("rdb2", ResidualDenseBlock(f, g, o));
  rdb3 = register_module("rdb3", ResidualDenseBlock(f, g, o));
}

torch::Tensor RRDBImpl::forward(const torch::Tensor& x) { return rdb3(rdb2(rdb1(x))) * kResidualScale + x; }

RRDBNetImpl::RRDBNetImpl(const RRDBNetConfig& c, const torch::TensorOptions& o) : config(c) {
  conv_first = register_module("conv_first", Conv2d(c.in_channels, c.num_feat, 3, 1, 1, true, o));
  auto list = register_module("body", torch::nn::ModuleList());
  for (int64_t i = 0; i < c.num_block; ++i) {
    body.push_back(RRDB(c.num_feat, c.num_grow, o));
    list->push_back(body.back());
  }
  conv_body = register_module("conv_body", Conv2d(c.num_feat, c.num_feat, 3, 1, 1, true, o));
  conv_up1 = register_module("conv_up1", Conv2d(c.num_feat, c.num_feat, 3, 1, 1, true, o));
  conv_up2 = register_module("conv_up2", Conv2d(c.num_feat, c.num_feat, 3, 1, 1, true, o));
  conv_hr = register_module("conv_hr", Conv2d(c.num_feat, c.num_feat, 3, 1, 1, true, o));
  conv_last = register_module("conv_last", Conv2d(c.num_feat, c.out_channels, 3, 1, 1, true, o));
}

torch::Tensor RRDBNetImpl::forward(const torch::Tensor& input) {
  if (RrdbCpuForward::applies(input, conv_first->weight)) return cpu_->forward(*this, input);
  return forward_layers(input);
}

torch::Tensor RRDBNetImpl::forward_layers(const torch::Tensor& input) {
  const torch::Tensor x = input.to(conv_first->weight.scalar_type());
  torch::Tensor feat = conv_first(x);
  torch::Tensor h = feat;
  for (auto& block : body) h = block(h);
  feat = feat + conv_body(h);
  namespace F = torch::nn::functional;
  const auto nearest2 = F::InterpolateFuncOptions().scale_factor(std::vector<double>{2.0, 2.0}).mode(torch::kNearest);
  feat = lrelu(conv_up1(F::interpolate(feat, nearest2)));
  feat = lrelu(conv_up2(F::interpolate(feat, nearest2)));
  return conv_last(lrelu(conv_hr(feat))).to(input.scalar_type()).contiguous();  // NCHW (bf16 runs channels-last)
}

RRDBNet load_rrdbnet(const std::filesystem::path& path) {
  const std::string source = path.string();
  TensorMap weights;
  if (is_onnx_path(path)) {
    const OnnxGraph graph = load_onnx(path);
    size_t convs = 0;
    for (const auto& node : graph.nodes) convs += node.op_type == "Conv";
    require(convs > kConvsOutsideBody && (convs - kConvsOutsideBody) % kConvsPerBlock == 0,
            source + ": has " + std::to_string(convs) + " Conv nodes; an RRDBNet x4 has 6 + 15 per block");
    // The names depend on the block count only: list them from a model on the meta device.
    RRDBNetConfig layout;
    layout.num_block = static_cast<int64_t>(convs - kConvsOutsideBody) / kConvsPerBlock;
    RRDBNet names(layout, torch::TensorOptions().device(torch::kMeta));
    weights = conv_weights_in_graph_order(graph, conv_module_names(*names), source);
  } else {
    weights = load_weights(path);
    for (const char* prefix : {"params_ema.", "params."}) {
      TensorMap inner = take_prefix(weights, prefix);
      if (!inner.empty()) {
        weights = std::move(inner);  // basicsr keeps at most these two; inference uses params_ema
        break;
      }
    }
  }
  RRDBNet model(RRDBNetConfig::from_weights(weights, source), torch::TensorOptions());
  load_state_dict(*model, weights, {}, source);
  return model;
}

}  // namespace u3d::nn
