#pragma once
// softmax(scale * scores) over the last dimension of bf16 attention scores, in place, for
// multi_head_attention (docs/networks.md, "bf16 kernels"). libtorch 1.13's bf16 softmax converts each row to
// fp32 and back in separate passes and calls a general exp: in a full-size bf16 UNet forward at 4,096
// tokens it took twice as long as the two attention products together. Here each row is read once for
// its maximum and once for exp and its sum, both in fp32, and rounded to bf16 once (nearest, ties to
// even). The attention scale is applied in fp32 inside the kernel, rather than to bf16 queries before
// the product.
#include <torch/torch.h>

namespace u3d::nn {

// Whether scaled_softmax_ takes `scores`: a contiguous bf16 CPU tensor.
bool scaled_softmax_applies(const torch::Tensor& scores);

// scores = softmax(scale * scores, -1) in place; scale > 0. Rows of -inf only give NaN, as ATen's softmax.
void scaled_softmax_(torch::Tensor& scores, double scale);

}  // namespace u3d::nn
