#pragma once
// GEGLU's gating, hidden * gelu(gate) with the exact (erf) GELU, of bf16 or fp32 activations in one
// pass, for the transformer feed-forward (docs/networks.md, "bf16 kernels"). Through ATen the two
// halves of the projection are separate strided views: the GELU (converting bf16 to fp32 and back)
// writes a new tensor, and the product reads both again. Here each output value is computed in fp32
// from the two inputs, and a bf16 one is rounded once (nearest, ties to even).
#include <torch/torch.h>

namespace u3d::nn {

// Whether geglu takes `projected`: a contiguous bf16 or fp32 CPU tensor whose last dimension is even.
bool geglu_applies(const torch::Tensor& projected);

// projected [..., 2n] = [hidden | gate] -> hidden * gelu(gate), [..., n], of projected's dtype.
torch::Tensor geglu(const torch::Tensor& projected);

}  // namespace u3d::nn
