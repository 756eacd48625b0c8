// libFuzzer target: image decoding. The bytes go through both entry points users reach: decode_image
// (textures embedded in glTF files, from memory) and load_image (view sets, OBJ/PLY textures, from a
// file). OpenCV does the decoding; it is not instrumented, so coverage guidance sees only our side, but
// ASan still catches what our code does with its results. When both succeed they must agree.
#include <cstdlib>
#include <optional>

#include "core/image.h"
#include "fuzz_common.h"
#include "io/image_codec.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // OpenCV accepts images up to 2^30 pixels, which a 100-byte PNG header can claim; the fuzz run's RSS
  // limit would report that as a crash. Cap it here (it is read once, on OpenCV's first use).
  setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "4194304", 1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::optional<u3d::Image> from_memory, from_file;
  u3d::fuzz::expect_clean([&] { from_memory = u3d::decode_image(data, size, "fuzz input"); });
  auto path = u3d::fuzz::write_scratch_file("input.img", data, size);
  u3d::fuzz::expect_clean([&] { from_file = u3d::load_image(path); });
  for (const auto* image : {&from_memory, &from_file}) {
    if (!*image) continue;
    const u3d::Image& im = **image;
    if (im.width <= 0 || im.height <= 0 || im.data.size() != im.pixel_count() * size_t(im.channels)) std::abort();
  }
  if (from_memory && from_file &&
      (from_memory->width != from_file->width || from_memory->height != from_file->height ||
       from_memory->channels != from_file->channels))
    std::abort();
  return 0;
}
