#include "nn/models/u2net.h"

#include "core/error.h"
#include "nn/checkpoint/onnx_weights.h"
#include "nn/checkpoint/state_dict_loader.h"
#include "nn/checkpoint/weights_file.h"

namespace u3d::nn {
namespace {

namespace F = torch::nn::functional;

// Stage names in registration (= forward) order, and each one's RSU levels (4F for 0).
const char* const kStageNames[] = {"stage1",  "stage2",  "stage3",  "stage4",  "stage5", "stage6",
                                   "stage5d", "stage4d", "stage3d", "stage2d", "stage1d"};
constexpr int kStageLevels[] = {7, 6, 5, 4, 0, 0, 0, 4, 5, 6, 7};
constexpr int kStages = 11;
constexpr int kSides = 6;

torch::Tensor pool(const torch::Tensor& x) {
  return F::max_pool2d(x, F::MaxPool2dFuncOptions(2).stride(2).ceil_mode(true));
}

torch::Tensor upsample_like(const torch::Tensor& x, const torch::Tensor& target) {
  if (x.size(2) == target.size(2) && x.size(3) == target.size(3)) return x;  // bilinear at scale 1 is the identity
  return F::interpolate(x, F::InterpolateFuncOptions()
                               .size(std::vector<int64_t>{target.size(2), target.size(3)})
                               .mode(torch::kBilinear)
                               .align_corners(false));
}

const torch::Tensor& conv_weight(const TensorMap& weights, const std::string& key, const std::string& source) {
  auto it = weights.find(key);
  require(it != weights.end(), source + ": no tensor '" + key + "' (not a U^2-Net / ISNet checkpoint?)");
  require(it->second.dim() == 4, source + ": tensor '" + key + "' has " + std::to_string(it->second.dim()) +
                                     " dimensions, a conv weight has 4");
  return it->second;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

U2NetConfig U2NetConfig::from_weights(const TensorMap& weights, const std::string& source) {
  U2NetConfig c;
  c.isnet = weights.count("conv_in.weight") > 0;
  for (const char* name : kStageNames) {
    const std::string stage(name);
    const torch::Tensor& in = conv_weight(weights, stage + ".rebnconvin.conv_s1.weight", source);
    const torch::Tensor& first = conv_weight(weights, stage + ".rebnconv1.conv_s1.weight", source);
    c.stages.push_back({in.size(1), first.size(0), in.size(0)});
  }
  c.in_channels = c.isnet ? conv_weight(weights, "conv_in.weight", source).size(1) : c.stages[0].in;
  c.out_channels = conv_weight(weights, "side1.weight", source).size(0);
  return c;
}

U2NetConfig U2NetConfig::layout(bool isnet) {
  U2NetConfig c;
  c.isnet = isnet;
  const int64_t first_in = isnet ? 64 : 3;
  c.stages = {{first_in, 16, 64}, {64, 16, 64},  {64, 16, 64},  {64, 16, 64},  {64, 16, 64}, {64, 16, 64},
              {128, 16, 64},      {128, 16, 64}, {128, 16, 64}, {128, 16, 64}, {128, 16, 64}};
  return c;
}

void fold_rebnconv_batchnorm(TensorMap& weights, const std::string& source) {
  std::vector<std::string> blocks;
  for (const auto& [key, value] : weights)
    if (ends_with(key, ".bn_s1.weight"))
      blocks.push_back(key.substr(0, key.size() - std::string(".bn_s1.weight").size()));
  auto take = [&](const std::string& key) {
    auto it = weights.find(key);
    require(it != weights.end(),
            source + ": no tensor '" + key + "' (a BatchNorm or conv of the checkpoint is incomplete)");
    torch::Tensor t = it->second.to(torch::kDouble);
    weights.erase(it);
    return t;
  };
  for (const std::string& m : blocks) {
    const torch::Tensor gamma = take(m + ".bn_s1.weight"), beta = take(m + ".bn_s1.bias");
    const torch::Tensor mean = take(m + ".bn_s1.running_mean"), var = take(m + ".bn_s1.running_var");
    weights.erase(m + ".bn_s1.num_batches_tracked");
    const torch::Tensor w = take(m + ".conv_s1.weight"), b = take(m + ".conv_s1.bias");
    require(w.dim() == 4 && gamma.numel() == w.size(0) && beta.numel() == w.size(0) && mean.numel() == w.size(0) &&
                var.numel() == w.size(0) && b.numel() == w.size(0),
            source + ": the shapes of '" + m + ".bn_s1.*' do not match '" + m + ".conv_s1.weight'");
    const torch::Tensor scale = gamma / torch::sqrt(var + kRebnConvBatchNormEps);
    weights[m + ".conv_s1.weight"] = (w * scale.view({-1, 1, 1, 1})).to(torch::kFloat);
    weights[m + ".conv_s1.bias"] = ((b - mean) * scale + beta).to(torch::kFloat);
  }
}

DilatedConv3x3Impl::DilatedConv3x3Impl(int64_t in, int64_t out, int64_t dilation_, int64_t stride_,
                                       const torch::TensorOptions& o)
    : dilation(dilation_), stride(stride_) {
  weight = register_parameter("weight", torch::empty({out, in, 3, 3}, o), false);
  bias = register_parameter("bias", torch::empty({out}, o), false);
}

torch::Tensor DilatedConv3x3Impl::forward(const torch::Tensor& x) {
  return torch::conv2d(x, weight, bias, {stride, stride}, {dilation, dilation}, {dilation, dilation});
}

RebnConvImpl::RebnConvImpl(int64_t in, int64_t out, int64_t dilation, const torch::TensorOptions& o) {
  conv_s1 = register_module("conv_s1", DilatedConv3x3(in, out, dilation, 1, o));
}

torch::Tensor RebnConvImpl::forward(const torch::Tensor& x) { return torch::relu(conv_s1(x)); }

RsuImpl::RsuImpl(int levels, bool dilated_, const RsuWidths& w, const torch::TensorOptions& o) : dilated(dilated_) {
  conv_in = register_module("rebnconvin", RebnConv(w.in, w.out, 1, o));
  for (int i = 1; i <= levels; ++i) {
    // RSU4F dilates 1, 2, 4, 8; RSU-L only its deepest conv, by 2.
    const int64_t dilation = dilated ? (int64_t{1} << (i - 1)) : (i == levels ? 2 : 1);
    encoder.push_back(
        register_module("rebnconv" + std::to_string(i), RebnConv(i == 1 ? w.out : w.mid, w.mid, dilation, o)));
  }
  for (int i = levels - 1; i >= 1; --i) {
    const int64_t dilation = dilated ? (int64_t{1} << (i - 1)) : 1;
    decoder.push_back(register_module("rebnconv" + std::to_string(i) + "d",
                                      RebnConv(2 * w.mid, i == 1 ? w.out : w.mid, dilation, o)));
  }
}

torch::Tensor RsuImpl::forward(const torch::Tensor& x) {
  const torch::Tensor hxin = conv_in(x);
  const size_t levels = encoder.size();
  std::vector<torch::Tensor> hx(levels);
  hx[0] = encoder[0](hxin);
  for (size_t i = 1; i < levels; ++i) {
    const bool pooled = !dilated && i + 1 < levels;  // RSU-L pools before rebnconv2..L-1
    hx[i] = encoder[i](pooled ? pool(hx[i - 1]) : hx[i - 1]);
  }
  torch::Tensor d = decoder[0](torch::cat({hx[levels - 1], hx[levels - 2]}, 1));
  for (size_t k = 1; k < decoder.size(); ++k) {
    const torch::Tensor& skip = hx[levels - 2 - k];
    d = decoder[k](torch::cat({upsample_like(d, skip), skip}, 1));
  }
  return d + hxin;
}

U2NetImpl::U2NetImpl(const U2NetConfig& c, const torch::TensorOptions& o) : config(c) {
  TORCH_CHECK(c.stages.size() == kStages, "U2Net: ", kStages, " stages expected");
  if (c.isnet) conv_in = register_module("conv_in", DilatedConv3x3(c.in_channels, c.stages[0].in, 1, 2, o));
  for (int i = 0; i < kStages; ++i) {
    const int levels = kStageLevels[i];
    stages.push_back(register_module(kStageNames[i], Rsu(levels ? levels : 4, levels == 0, c.stages[i], o)));
  }
  // side1..side5 read the decoder stage1d..stage5d, side6 the deepest encoder stage6.
  for (int k = 1; k <= kSides; ++k) {
    const int64_t in = k == kSides ? c.stages[5].out : c.stages[kStages - k].out;
    sides.push_back(register_module("side" + std::to_string(k), DilatedConv3x3(in, c.out_channels, 1, 1, o)));
  }
  if (!c.isnet) outconv = register_module("outconv", Conv2d(kSides * c.out_channels, c.out_channels, 1, 1, 0, true, o));
}

std::vector<torch::Tensor> U2NetImpl::forward(const torch::Tensor& input) {
  const torch::Tensor x = input.to(stages[0]->conv_in->conv_s1->weight.scalar_type());
  // Encoder: stage1..6, pooled in between.
  std::vector<torch::Tensor> enc;
  torch::Tensor h = config.isnet ? conv_in(x) : x;
  for (int i = 0; i < 6; ++i) {
    h = stages[i](i == 0 ? h : pool(enc.back()));
    enc.push_back(h);
  }
  // Decoder: stage5d..1d; dec[k] is the output at level k+1 (dec[5] = hx6).
  std::vector<torch::Tensor> dec(6);
  dec[5] = enc[5];
  for (int level = 4; level >= 0; --level)
    dec[level] = stages[kStages - 1 - level](torch::cat({upsample_like(dec[level + 1], enc[level]), enc[level]}, 1));

  std::vector<torch::Tensor> logits;
  for (int k = 0; k < kSides; ++k) logits.push_back(upsample_like(sides[k](dec[k]), x));  // all at the input size
  std::vector<torch::Tensor> out;
  if (!config.isnet) out.push_back(torch::sigmoid(outconv(torch::cat(logits, 1))).to(input.scalar_type()));
  for (const auto& l : logits) out.push_back(torch::sigmoid(l).to(input.scalar_type()));
  if (config.isnet)
    for (const auto& f : dec) out.push_back(f.to(input.scalar_type()));
  for (auto& t : out) t = t.contiguous();  // NCHW for the caller (bf16 convolutions work channels-last)
  return out;
}

TensorMap read_u2net_weights(const std::filesystem::path& path) {
  const std::string source = path.string();
  if (!is_onnx_path(path)) {
    TensorMap weights = load_weights(path);
    fold_rebnconv_batchnorm(weights, source);
    return weights;
  }
  const OnnxGraph graph = load_onnx(path);
  const OnnxNode* last = nullptr;
  for (const auto& node : graph.nodes)
    if (node.op_type == "Conv") last = &node;
  require(last && last->inputs.size() >= 2 && graph.initializers.count(last->inputs[1]) &&
              graph.initializers.at(last->inputs[1]).dim() == 4,
          source + ": no Conv node with an initializer weight (not a U^2-Net / ISNet export?)");
  const bool isnet = graph.initializers.at(last->inputs[1]).size(3) == 3;
  U2Net names(U2NetConfig::layout(isnet), torch::TensorOptions().device(torch::kMeta));
  return conv_weights_in_graph_order(graph, conv_module_names(*names), source);
}

U2Net build_u2net(const TensorMap& weights, const std::string& source) {
  U2Net model(U2NetConfig::from_weights(weights, source), torch::TensorOptions());
  load_state_dict(*model, weights, {}, source);
  return model;
}

U2Net load_u2net(const std::filesystem::path& path) { return build_u2net(read_u2net_weights(path), path.string()); }

}  // namespace u3d::nn
