#pragma once
// LayerNorm over the last dimension of bf16 activations with fp32 weight and bias in one pass over
// memory, for the LayerNorm layer (docs/networks.md, "bf16 kernels"). Through ATen a bf16 tensor is
// converted to an fp32 copy, normalised into a second fp32 tensor and converted back: three passes and
// two temporaries of twice the input's size, for each of a transformer block's three norms. Here each
// row (at most a few thousand values, in L1) is read for its mean, again for the sum of squared
// deviations from it (two passes in fp32, as exact as ATen's fp32 statistics or more), and a third time
// to write (x - mean) * rstd * weight + bias rounded once to bf16 (nearest, ties to even). A row's result
// does not depend on the thread count.
#include <torch/torch.h>

namespace u3d::nn {

// Whether layer_norm_bf16 takes `x`: a contiguous bf16 CPU tensor whose last dimension is the size of
// `weight` and `bias`, both contiguous fp32 vectors.
bool layer_norm_bf16_applies(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias);

// layer_norm(x, {weight.size(0)}, weight, bias, eps), computed in fp32, of x's dtype (bf16).
torch::Tensor layer_norm_bf16(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias,
                              double eps);

}  // namespace u3d::nn
