// libFuzzer target: the Wavefront material library reader (read_mtl). Texture paths are only resolved,
// not loaded, so nothing outside the input file is read.
#include "fuzz_common.h"
#include "io/mtl_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto path = u3d::fuzz::write_scratch_file("input.mtl", data, size);
  u3d::fuzz::expect_clean([&] { u3d::read_mtl(path); });
  return 0;
}
