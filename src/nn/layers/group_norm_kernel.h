#pragma once
// GroupNorm (optionally followed by SiLU) of channels-last bf16 or fp32 activations in one kernel, for
// the GroupNorm layer (docs/networks.md, "bf16 kernels"). The convolutions return channels-last
// tensors (nn/layers/onednn_conv.h); through ATen each norm of a bf16 one would convert it to fp32,
// normalise, convert back and apply SiLU in a fourth pass, and ATen's fp32 GroupNorm of a channels-last
// tensor loses precision at large offsets. Here statistics and scaling are computed in fp32 (the sums
// of each block of pixels in fp32, the blocks summed in double) from the values directly, and a bf16
// result is rounded once, as ATen rounds (nearest, ties to even). The blocks do not depend on the
// thread count, so the result does not either.
#include <torch/torch.h>

namespace u3d::nn {

// Whether group_norm_channels_last takes `x`: a 4-D channels-last bf16 or fp32 tensor on the CPU, with
// fp32 weight and bias of its channel count.
bool group_norm_channels_last_applies(const torch::Tensor& x, const torch::Tensor& weight);

// group_norm(x, groups, weight, bias, eps), then x * sigmoid(x) if `silu`; channels-last, of x's dtype.
torch::Tensor group_norm_channels_last(const torch::Tensor& x, int64_t groups, const torch::Tensor& weight,
                                       const torch::Tensor& bias, double eps, bool silu);

}  // namespace u3d::nn
