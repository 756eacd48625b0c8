// libFuzzer target: the zip directory of .pth checkpoints (nn/checkpoint/zip_crc), which reads the
// end-of-directory record, the zip64 locator and record, and every central-directory entry with its
// extra fields, and checks that each entry's data lies inside the file. zip_crc.cpp needs only
// libtorch's header-only CRC code, so it is compiled into the target directly (fuzz/CMakeLists.txt).
#include "fuzz_common.h"
#include "nn/checkpoint/zip_crc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto path = u3d::fuzz::write_scratch_file("input.pth", data, size);
  u3d::fuzz::expect_clean([&] { u3d::nn::zip_records(path); });
  return 0;
}
