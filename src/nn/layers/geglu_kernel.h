#pragma once
// GEGLU's gating, hidden * gelu(gate) with the exact (erf) GELU, of bf16 activations in one pass, for
// the transformer feed-forward (docs/networks.md, "bf16 kernels"). Through ATen the two halves of the
// projection are separate strided views: the GELU converts its half to fp32 and back and writes a
// new tensor, and the product reads both again. Here each output value is computed in fp32 from the
// two bf16 inputs and rounded to bf16 once (nearest, ties to even).
#include <torch/torch.h>

namespace u3d::nn {

// Whether geglu_bf16 takes `projected`: a contiguous bf16 CPU tensor whose last dimension is even.
bool geglu_bf16_applies(const torch::Tensor& projected);

// projected [..., 2n] = [hidden | gate] -> hidden * gelu(gate), [..., n], bf16.
torch::Tensor geglu_bf16(const torch::Tensor& projected);

}  // namespace u3d::nn
