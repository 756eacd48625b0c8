#pragma once
// Fused multi-head attention on the CPU, fp32 and bf16, for multi_head_attention (docs/networks.md,
// "Fused attention"). Each head's queries go in tiles of 32 against its keys in blocks of 64, with an
// online softmax: a block's scores are computed into a small buffer that stays in L1, the running
// maximum and sum of every query are updated and the output accumulator rescaled when the maximum
// grows, then the block's probabilities are multiplied by its values. No query's whole score row is ever
// stored. Scores, softmax and the output accumulate in fp32; the attention scale is applied in fp32 to
// the unscaled product. bf16 inputs take avx512_bf16 dot products (vdpbf16ps: bf16 products summed in
// fp32), the probabilities rounded to bf16 before their product with the values, and the output is
// rounded once at the end. fp32 inputs take FMAs; that kernel is compiled for AVX-512, AVX2 and the
// baseline and picked when the program loads (nn/layers/vector_math.h).
#include <torch/torch.h>

namespace u3d::nn {

// Whether fused_attention takes these inputs: q [B, Lq, H*D], k and v [B, Lk, H*D] on the CPU, all fp32
// or all bf16 (bf16 only on a CPU with avx512_bf16), D a multiple of 8 up to 256, Lq and Lk not 0.
bool fused_attention_applies(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v, int64_t heads);

// softmax(q·kᵀ·scale)·v per head, q [B, Lq, H*D], k and v [B, Lk, H*D] -> [B, Lq, H*D] in q's dtype;
// scale > 0. The tensors may be strided views as long as their channels are contiguous.
torch::Tensor fused_attention(const torch::Tensor& q, const torch::Tensor& k, const torch::Tensor& v, int64_t heads,
                              double scale);

}  // namespace u3d::nn
