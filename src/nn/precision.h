#pragma once
// Numeric precision of a network: which floating type its weights and activations use, the default
// for a device, and the conversion of a built model. The convention (docs/networks.md, "Precision"):
// convolutions, linear layers, attention products and embeddings run in the model's precision;
// GroupNorm/LayerNorm keep fp32 weights and compute in fp32 (libtorch 1.13's bf16 norms accumulate in
// bf16: slow and inaccurate), softmax runs in fp32, and models take and return tensors in the caller's
// dtype, so schedulers and everything outside the networks stay fp32.
#include <torch/torch.h>

#include "nn/precision_kind.h"

namespace u3d::nn {

torch::ScalarType scalar_type(Precision precision);

// Whether this CPU has native bf16 dot products (avx512_bf16) that oneDNN uses for bf16 convolutions
// and matrix products. Without them libtorch emulates bf16 and is slower than fp32.
bool cpu_has_bf16_kernels();

// The precision networks run in on `device` when the user does not choose: bf16 on a CPU with
// avx512_bf16, fp32 on other CPUs, fp16 on CUDA.
Precision default_precision(const torch::Device& device);

// An Error when `precision` cannot run on `device`: fp16 needs CUDA (libtorch 1.13 has no fp16 CPU
// convolutions).
void check_precision_supported(Precision precision, const torch::Device& device);

// Converts every floating parameter and buffer of `model` to `precision`, except those of GroupNorm
// and LayerNorm modules, which become fp32. Done once after loading; converting back to fp32 does not
// restore the dropped mantissa bits.
void set_precision(torch::nn::Module& model, Precision precision);

// The same types for a model that is built but not loaded yet, called once before loading it: its
// parameters get fresh, uninitialised storage of their type in `precision`, all in one block (their
// values are not read, and are lost), its buffers are converted. Loading then converts the checkpoint
// once, straight into that type (an fp16 file into a bf16 model), instead of into fp32 and again by
// set_precision.
void allocate_in_precision(torch::nn::Module& model, Precision precision);

}  // namespace u3d::nn
