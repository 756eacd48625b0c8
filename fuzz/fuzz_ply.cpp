// libFuzzer target: PLY (ascii and both binary encodings) through read_mesh (the reader plus
// Mesh::validate). A "comment TextureFile t.png" line reaches the companion texture (mesh_companions.h).
#include "fuzz_common.h"
#include "io/mesh_io.h"
#include "mesh_companions.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  u3d::fuzz::write_mesh_companions();
  auto path = u3d::fuzz::write_scratch_file("input.ply", data, size);
  u3d::fuzz::expect_clean([&] { u3d::read_mesh(path); });
  return 0;
}
