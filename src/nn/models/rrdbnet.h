#pragma once
// RRDBNet, the generator of ESRGAN / Real-ESRGAN at scale 4 (Real-ESRGAN x4plus: 64 features, 23 blocks,
// growth 32), with basicsr's parameter names: conv_first, body.<i>.rdb<1..3>.conv<1..5>, conv_body,
// conv_up1, conv_up2, conv_hr, conv_last. Every conv is 3x3 with bias; LeakyReLU slope 0.2; each dense
// block and each RRDB adds 0.2 times its output to its input; the upsampler is nearest x2 and a conv,
// twice. The widths and the block count come from the checkpoint's shapes, so any RRDBNet x4 loads.
#include <torch/torch.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nn/checkpoint/tensor_map.h"
#include "nn/layers/layers.h"
#include "nn/models/rrdbnet_cpu.h"

namespace u3d::nn {

struct RRDBNetConfig {
  int64_t in_channels = 3;
  int64_t out_channels = 3;
  int64_t num_feat = 64;
  int64_t num_block = 23;
  int64_t num_grow = 32;

  // Reads the widths and the block count from basicsr-named weights; an Error names `source` and the
  // tensor when one is missing or has an unexpected rank.
  static RRDBNetConfig from_weights(const TensorMap& weights, const std::string& source);
};

class ResidualDenseBlockImpl : public torch::nn::Module {
 public:
  ResidualDenseBlockImpl(int64_t num_feat, int64_t num_grow, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  Conv2d conv1{nullptr}, conv2{nullptr}, conv3{nullptr}, conv4{nullptr}, conv5{nullptr};
};
TORCH_MODULE(ResidualDenseBlock);

class RRDBImpl : public torch::nn::Module {
 public:
  RRDBImpl(int64_t num_feat, int64_t num_grow, const torch::TensorOptions& options);
  torch::Tensor forward(const torch::Tensor& x);
  ResidualDenseBlock rdb1{nullptr}, rdb2{nullptr}, rdb3{nullptr};
};
TORCH_MODULE(RRDB);

class RRDBNetImpl : public torch::nn::Module {
 public:
  RRDBNetImpl(const RRDBNetConfig& config, const torch::TensorOptions& options);
  // [N, in, H, W] -> [N, out, 4H, 4W], raw (not clamped); runs in the weights' dtype and returns x's.
  // On the CPU through oneDNN without copies between the layers (nn/models/rrdbnet_cpu.h), elsewhere
  // layer by layer.
  torch::Tensor forward(const torch::Tensor& x);
  // The same, layer by layer through the modules on any device (the CPU path's reference in tests).
  torch::Tensor forward_layers(const torch::Tensor& x);
  // The CPU path keeps its buffers from one call to the next while `keep` (RrdbCpuForward::keep_workspace).
  void keep_workspace(bool keep) { cpu_->keep_workspace(keep); }
  RRDBNetConfig config;
  Conv2d conv_first{nullptr}, conv_body{nullptr}, conv_up1{nullptr}, conv_up2{nullptr}, conv_hr{nullptr},
      conv_last{nullptr};
  std::vector<RRDB> body;

 private:
  std::shared_ptr<RrdbCpuForward> cpu_ = std::make_shared<RrdbCpuForward>();
};
TORCH_MODULE(RRDBNet);

// Builds and strictly loads an RRDBNet (fp32, CPU) from
//  - an ONNX export (.onnx, e.g. Unique3D's ckpt/realesrgan-x4.onnx): the Conv nodes in graph order;
//  - a basicsr checkpoint (.pth / safetensors): the state dict itself, or its "params_ema" entry (the
//    one Real-ESRGAN's inference uses), else its "params" entry, as RealESRGAN_x4plus.pth stores them.
// Errors name the file and the tensor.
RRDBNet load_rrdbnet(const std::filesystem::path& path);

}  // namespace u3d::nn
