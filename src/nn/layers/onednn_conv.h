#pragma once
// 2-D convolution of bf16 or fp32 activations on the CPU through oneDNN directly, for the Conv2d layer
// (docs/networks.md, "bf16 kernels" and "The fp32 path"). Through ATen (libtorch 1.13) every such
// convolution reorders its weights into oneDNN's blocked layout on every call and converts the
// activations to and from a blocked layout too: at full size that was 0.4 s of a 3.3 s bf16 UNet
// forward, and ATen's kernel choice for 2,560 input channels ran at a quarter of the others' speed.
// Here the weights are reordered once into the layout the kernel asks for, and the activations stay
// channels-last (NHWC), the layout the kernel reads and writes itself: the output is a channels-last
// tensor, and the element-wise ops after it (norms, SiLU, residual adds, concatenation, upsampling)
// keep that layout.
#include <torch/torch.h>

#include <memory>

namespace u3d::nn {

class OnednnConv2d {
 public:
  // Whether this path runs `x` through `weight`: both on the CPU and of one dtype, fp32 on any CPU, bf16
  // with avx512_bf16 (elsewhere oneDNN has no bf16 kernels and ATen's emulation stays).
  static bool applies(const torch::Tensor& x, const torch::Tensor& weight);

  OnednnConv2d();
  ~OnednnConv2d();

  // conv2d(x, weight, bias) with square stride and symmetric padding; the result is channels-last.
  // Plans (the kernel and its packed weights) are kept per input shape; they are rebuilt when the weight
  // tensor is replaced or modified in place (its storage or version changes).
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias, int64_t stride,
                        int64_t padding);

  // From now on the weights are packed into the weight tensor's own storage (where the packed layout fits
  // in its bytes, as it does for channel counts that are multiples of 16) instead of into a second
  // copy: no memory beyond the checkpoint's, and no reorder on any later call. The tensor then holds
  // oneDNN's layout, not the checkpoint's values, so only a model that serves forward passes and is
  // not read or converted afterwards may do this (the pipelines' loaded networks, docs/networks.md
  // "bf16 kernels"). Replacing or modifying the tensor afterwards (set_data, copy_) packs the new
  // values again.
  void pack_in_place();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace u3d::nn
