#include "nn/schedulers/noise_source.h"

#include <ATen/CPUGeneratorImpl.h>

namespace u3d::nn {

SeededNoise::SeededNoise(uint64_t seed) : generator_(at::detail::createCPUGenerator(seed)) {}

torch::Tensor SeededNoise::randn(at::IntArrayRef shape, torch::ScalarType dtype) {
  return torch::randn(shape, generator_, torch::TensorOptions().dtype(dtype));
}

}  // namespace u3d::nn
