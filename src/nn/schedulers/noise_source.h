#pragma once
// Where the samplers' Gaussian noise comes from. Injectable so tests can replay recorded noise and
// users get reproducible runs from a seed.
#include <torch/torch.h>

#include <cstdint>

namespace u3d::nn {

class NoiseSource {
 public:
  virtual ~NoiseSource() = default;
  // A standard-normal tensor of the given shape and dtype, on the CPU.
  virtual torch::Tensor randn(at::IntArrayRef shape, torch::ScalarType dtype = torch::kFloat32) = 0;
};

// torch's CPU generator seeded with `seed`: the same stream as Python's
// torch.randn(..., generator=torch.Generator().manual_seed(seed)), as diffusers draws it on the CPU.
class SeededNoise : public NoiseSource {
 public:
  explicit SeededNoise(uint64_t seed);
  torch::Tensor randn(at::IntArrayRef shape, torch::ScalarType dtype = torch::kFloat32) override;

 private:
  at::Generator generator_;
};

}  // namespace u3d::nn
