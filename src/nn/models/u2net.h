#pragma once
// U^2-Net (U2NET / U2NETP, rembg's u2net.onnx and u2netp.onnx) and ISNet (DIS's ISNetDIS, rembg's
// isnet-general-use.onnx and imgly's background-removal models), with the upstream parameter names.
// Both are nested U-structures of RSU blocks: an encoder of stage1..stage6 (RSU7, RSU6, RSU5, RSU4,
// RSU4F, RSU4F) joined by 2x2 max-pools with ceil mode, a decoder stage5d..stage1d fed by bilinear
// (half-pixel) upsampling and concatenation, and 3x3 side convs side1..side6 whose sigmoids are the
// outputs. U2NET fuses the six side maps with a 1x1 `outconv` (its first output, d0); ISNet instead
// starts with a stride-2 3x3 `conv_in` and has no fused output (d1 is its mask).
//
// Every REBNCONV (conv 3x3 with dilation, BatchNorm, ReLU) is held with its BatchNorm folded into the
// conv, as ONNX exports store it: parameters `<block>.conv_s1.{weight,bias}`. A state dict with the
// BatchNorm (`<block>.bn_s1.*`) is folded on loading (fold_rebnconv_batchnorm). All widths come from the
// weights, so U2NET, U2NETP and reduced-width variants load alike.
#include <torch/torch.h>

#include <filesystem>
#include <string>
#include <vector>

#include "nn/checkpoint/tensor_map.h"
#include "nn/layers/layers.h"

namespace u3d::nn {

struct RsuWidths {
  int64_t in = 0, mid = 0, out = 0;
};

struct U2NetConfig {
  bool isnet = false;  // ISNetDIS: conv_in before stage1, no outconv
  int64_t in_channels = 3;
  int64_t out_channels = 1;
  std::vector<RsuWidths> stages;  // stage1..stage6, then stage5d..stage1d (11 blocks)

  // Reads every width from the (folded) weights; `isnet` when they hold conv_in.weight. An Error names
  // `source` and the first tensor that is missing or of the wrong rank.
  static U2NetConfig from_weights(const TensorMap& weights, const std::string& source);
  // U2NETP's widths: a valid network of the given kind, for listing its parameter names.
  static U2NetConfig layout(bool isnet);
};

// eps of upstream's BatchNorm2d layers.
inline constexpr double kRebnConvBatchNormEps = 1e-5;

// Replaces every `<m>.conv_s1.{weight,bias}` + `<m>.bn_s1.{weight,bias,running_mean,running_var}`
// (and the ignored `num_batches_tracked`) by the folded conv, computed in float64:
// W' = W γ / sqrt(var + eps) per output channel, b' = (b − mean) γ / sqrt(var + eps) + β.
// An Error names `source` and the tensor when a BatchNorm lacks one of its tensors or its conv.
void fold_rebnconv_batchnorm(TensorMap& weights, const std::string& source);

// A 3x3 convolution with bias, dilation d and padding d (the size is kept).
class DilatedConv3x3Impl : public torch::nn::Module {
 public:
  DilatedConv3x3Impl(int64_t in, int64_t out, int64_t dilation, int64_t stride, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  torch::Tensor weight, bias;
  int64_t dilation, stride;
};
TORCH_MODULE(DilatedConv3x3);

// REBNCONV with the BatchNorm folded: relu(conv_s1(x)).
class RebnConvImpl : public torch::nn::Module {
 public:
  RebnConvImpl(int64_t in, int64_t out, int64_t dilation, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  DilatedConv3x3 conv_s1{nullptr};
};
TORCH_MODULE(RebnConv);

// RSU-L (levels 4..7: rebnconvin, rebnconv1..L with pooling between 1..L-1 and dilation 2 at L, decoder
// rebnconv(L-1)d..1d) or RSU4F (no pooling: dilations 1, 2, 4, 8), with the residual hx1d + hxin.
class RsuImpl : public torch::nn::Module {
 public:
  RsuImpl(int levels, bool dilated, const RsuWidths& widths, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  RebnConv conv_in{nullptr};      // registered as rebnconvin
  std::vector<RebnConv> encoder;  // rebnconv1..L
  std::vector<RebnConv> decoder;  // rebnconv(L-1)d..1d
  bool dilated;
};
TORCH_MODULE(Rsu);

class U2NetImpl : public torch::nn::Module {
 public:
  U2NetImpl(const U2NetConfig& config, const torch::TensorOptions& options);
  // x [N, 3, H, W] -> the upstream outputs in their order: U2NET d0 (fused), d1..d6; ISNet d1..d6 then
  // the decoder features hx1d, hx2d, hx3d, hx4d, hx5d, hx6. The d* are sigmoids at the input size.
  // Runs in the weights' dtype and returns x's.
  std::vector<torch::Tensor> forward(const torch::Tensor& x);
  U2NetConfig config;
  DilatedConv3x3 conv_in{nullptr};  // ISNet only
  std::vector<Rsu> stages;          // stage1..6, stage5d..1d
  std::vector<DilatedConv3x3> sides;
  Conv2d outconv{nullptr};  // U2NET only
};
TORCH_MODULE(U2Net);

// The weights of a U^2-Net or ISNet under the model's parameter names, in the file's dtype, from an ONNX
// export (.onnx: the Conv nodes in graph order; the kind from the last Conv, U2NET's 1x1 outconv or
// ISNet's 3x3 side6) or a state dict with or without BatchNorm (.pth / safetensors, folded here).
TensorMap read_u2net_weights(const std::filesystem::path& path);

// Builds the network the weights describe (fp32, CPU) and loads them strictly; errors name `source`
// and the tensor.
U2Net build_u2net(const TensorMap& weights, const std::string& source);

// build_u2net(read_u2net_weights(path), path).
U2Net load_u2net(const std::filesystem::path& path);

}  // namespace u3d::nn
