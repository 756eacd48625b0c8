// libFuzzer target: image decoding (core/image_decode: PNG through libpng, JPEG through libjpeg, anything
// else refused). The bytes go through both entry points users reach: decode_image (textures embedded in
// glTF files, from memory) and load_image (view sets, OBJ/PLY textures, from a file). libpng and libjpeg
// are not instrumented, so coverage guidance sees only our side, but ASan still catches what our code
// does with their results. When both succeed they must agree.
#include <cstdlib>
#include <optional>

#include "core/image.h"
#include "core/image_decode.h"
#include "core/progress.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  u3d::set_progress_quiet(true);  // the decoders' warning lines, one or more for most mutated inputs
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (u3d::fuzz::claims_a_huge_image(data, size)) return 0;
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
