#pragma once
// GroupNorm (optionally followed by SiLU) of channels-last bf16 activations in one kernel, for the
// GroupNorm layer (docs/networks.md, "bf16 kernels"). The bf16 convolutions return channels-last
// tensors; through ATen each norm of one would convert it to fp32, normalise, convert back and apply
// SiLU in a fourth pass. Here statistics and scaling are computed in fp32 (the sums of each block of
// pixels in fp32, the blocks summed in double) from the bf16 values directly, and the result is rounded
// to bf16 once, as ATen rounds (nearest, ties to even). The blocks do not depend on the thread count,
// so the result does not either.
#include <torch/torch.h>

namespace u3d::nn {

// Whether group_norm_channels_last takes `x`: a 4-D channels-last bf16 tensor on the CPU, with fp32
// weight and bias of its channel count.
bool group_norm_channels_last_applies(const torch::Tensor& x, const torch::Tensor& weight);

// group_norm(x, groups, weight, bias, eps), then x * sigmoid(x) if `silu`; channels-last bf16 like x.
torch::Tensor group_norm_channels_last(const torch::Tensor& x, int64_t groups, const torch::Tensor& weight,
                                       const torch::Tensor& bias, double eps, bool silu);

}  // namespace u3d::nn
