// libFuzzer target: glTF through read_mesh (tinygltf's parser, our mesh builder, Mesh::validate).
// Input starting with the GLB magic "glTF" is read as .glb, anything else as .gltf JSON; a .gltf may
// refer to the companion texture t.png (mesh_companions.h) or carry data URIs.
#include <cstring>

#include "fuzz_common.h"
#include "io/mesh_io.h"
#include "mesh_companions.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (u3d::fuzz::claims_a_huge_image(data, size)) return 0;  // an embedded texture's size (fuzz_common.h)
  u3d::fuzz::write_mesh_companions();
  bool binary = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  // A .gltf may name the other input file as a buffer: remove the previous input so every run reads
  // only what this input says.
  std::filesystem::remove(u3d::fuzz::scratch_dir() / (binary ? "input.gltf" : "input.glb"));
  auto path = u3d::fuzz::write_scratch_file(binary ? "input.glb" : "input.gltf", data, size);
  u3d::fuzz::expect_clean([&] { u3d::read_mesh(path); });
  return 0;
}
