#pragma once
// fp32 linear layers on CPUs with AVX-512 through oneDNN's matrix product (dnnl_sgemm), for the Linear
// layer (docs/networks.md, "The fp32 path"). Through ATen (libtorch 1.13) they go to OpenBLAS, and
// Debian's 0.3.21 runs its AVX2 kernel (sgemm_kernel_HASWELL in perf) on the Zen 5 build machine: on
// the UNet's shapes (8,192 x 320 x 2,560 down to 512 x 5,120 x 1,280) it did 1.6-3x less arithmetic
// per CPU second than oneDNN's AVX-512 kernel. Other precisions, and CPUs without AVX-512 (not
// measured), keep ATen's path.
#include <torch/torch.h>

namespace u3d::nn {

// Whether onednn_linear takes `x` through `weight`: both fp32 on the CPU, on a CPU with AVX-512.
bool onednn_linear_applies(const torch::Tensor& x, const torch::Tensor& weight);

// torch::linear(x, weight, bias): x [..., in] times weight [out, in] transposed, plus bias [out] when
// defined; a new contiguous tensor [..., out].
torch::Tensor onednn_linear(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias);

}  // namespace u3d::nn
