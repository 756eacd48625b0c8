#pragma once
// RRDBNet's forward on the CPU through oneDNN, without a copy between its convolutions
// (docs/networks.md, "Real-ESRGAN on the CPU"). The activations live in oneDNN's channel-blocked layout
// (nChw16c with AVX-512, nChw8c without), in which the first C channels of an image are one contiguous
// run of memory. So a dense block's five convolutions share one buffer of feat + 4 x grow channels:
// each reads the prefix that holds its input and writes its output right after it, and the block's
// concatenations cost nothing. The LeakyReLUs, the 0.2-scaled residual sums and the trunk's skip
// connection are the convolutions' post-ops (computed in fp32 and rounded once), the nearest x2
// upsampling is oneDNN's resampling. Widths that are not a multiple of the block get padding channels
// whose weights are zero, so every RRDBNet runs here. fp32 on any CPU, bf16 with avx512_bf16.
#include <torch/torch.h>

#include <memory>

namespace u3d::nn {

class RRDBNetImpl;

class RrdbCpuForward {
 public:
  // Whether this path runs `x` through a network whose weights are like `weight`: a CPU input
  // [N, C, H, W] of fp32 or bf16 and fp32 weights, or bf16 weights on a CPU with bf16 kernels.
  static bool applies(const torch::Tensor& x, const torch::Tensor& weight);

  RrdbCpuForward();
  ~RrdbCpuForward();

  // net.forward(x): [N, in, H, W] -> [N, out, 4H, 4W] in x's dtype, contiguous. The packed weights are
  // made on the first call and again when a weight tensor of `net` is replaced or modified in place;
  // the kernels are kept per input size.
  torch::Tensor forward(const RRDBNetImpl& net, const torch::Tensor& x);

  // Whether forward keeps its buffers (activations of every size it needs, about 0.5 GB in bf16 for a
  // 266 px tile) for the next call instead of mapping them anew: on while the tiles of a set of images
  // run (nn/pipelines/upscale.h), off (and the buffers freed) afterwards.
  void keep_workspace(bool keep);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace u3d::nn
