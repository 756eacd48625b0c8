// libFuzzer target: safetensors weights files (nn/checkpoint/safetensors), the format of every diffusers
// and converted checkpoint. The file is read twice, as the networks read it: its header alone
// (inspect_safetensors, what a weights check before loading does) and whole (load_safetensors), which
// copies every tensor out of the memory-mapped file. safetensors.cpp is compiled into the target, which
// links libtorch for the tensors (fuzz/CMakeLists.txt).
#include "fuzz_common.h"
#include "nn/checkpoint/safetensors.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto path = u3d::fuzz::write_scratch_file("weights.safetensors", data, size);
  u3d::fuzz::expect_clean([&] { u3d::nn::inspect_safetensors(path); });
  u3d::fuzz::expect_clean([&] { u3d::nn::load_safetensors(path); });
  return 0;
}
