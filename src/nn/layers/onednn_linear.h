#pragma once
// Linear layers of bf16 or fp32 activations on the CPU through oneDNN's matrix product directly, for
// the Linear layer (docs/networks.md, "bf16 kernels" and "The fp32 path"). Through ATen (libtorch
// 1.13) fp32 goes to OpenBLAS, whose AVX2 kernel Debian's 0.3.21 runs on the Zen 5 build machine (1.6-3x
// less arithmetic per CPU second than oneDNN's AVX-512 kernel on the UNet's shapes), and bf16 to oneDNN
// with the weights in their plain layout, which the kernel repacks block by block on every call. Here
// the weights are either read in their plain layout (no copy: fp32 runs as fast that way) or, once a
// loaded network asks for it, packed into their own storage in the layout the kernel reads (bf16
// products at 750-800 GFLOP/s against 510-680 from the plain layout on the UNet's shapes, 2 threads of
// the Zen 5 host). CPUs without AVX-512 keep ATen's path for fp32 (not measured there).
#include <torch/torch.h>

#include <memory>

namespace u3d::nn {

class OnednnLinear {
 public:
  // Whether this path runs `x` through `weight`: both on the CPU and of one dtype, a 2-D weight, fp32 on
  // a CPU with AVX-512, bf16 with avx512_bf16.
  static bool applies(const torch::Tensor& x, const torch::Tensor& weight);

  OnednnLinear();
  ~OnednnLinear();

  // What the product's outputs go through, in fp32 after the bias and before the one rounding: nothing,
  // the exact (erf) GELU, or a product with `factor` (a contiguous tensor of the output's shape and dtype).
  enum class Epilogue { none, gelu, multiply };

  // torch::linear(x, weight, bias): x [..., in] times weight [out, in] transposed, plus bias [out] (of the
  // weights' dtype or fp32, added before the one rounding) when defined, through `epilogue`; a new
  // contiguous tensor [..., out]. Plans are kept per row count and epilogue; they are rebuilt when the
  // weight tensor is replaced or modified in place (its storage or version changes).
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias,
                        Epilogue epilogue = Epilogue::none, const torch::Tensor& factor = {});

  // Packs `weight` (the layer's) into its own storage now, and again whenever it gets new values, where
  // this path applies to it and the kernel's layout fits in its bytes (as it does for the networks'
  // sizes: outputs a multiple of 64 here); it is read from there. As OnednnConv2d::pack_in_place, the
  // tensor then holds oneDNN's layout, not the checkpoint's values. Packing now, not in the first
  // forward pass, keeps the reorder's buffer out of that pass's peak memory.
  void pack_in_place(const torch::Tensor& weight);

  // Whether the weight tensor holds the packed layout now (no other path may read it then).
  bool holds_packed_weights() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace u3d::nn
