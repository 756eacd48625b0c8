// libFuzzer target: torch.save checkpoints (.pth, diffusers' .bin) as whole files
// (nn/checkpoint/pth_reader): the zip archive through libtorch's reader (PyTorchStreamReader), the zip
// directory and CRC checks of zip_crc, then the pickle and the tensor records. Every record is checked
// against its CRC, so mutations of the pickle rarely get past that check here: fuzz_state_dict fuzzes
// the pickle inside a well-formed archive. The readers' sources are compiled into the target, which links
// libtorch (fuzz/CMakeLists.txt); libtorch itself is not instrumented, so only crashes inside it (not
// its out-of-bounds reads) are seen.
#include "fuzz_common.h"
#include "nn/checkpoint/pth_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto path = u3d::fuzz::write_scratch_file("weights.pth", data, size);
  u3d::fuzz::expect_clean([&] { u3d::nn::inspect_pth(path); });
  u3d::fuzz::expect_clean([&] { u3d::nn::load_pth(path); });
  return 0;
}
