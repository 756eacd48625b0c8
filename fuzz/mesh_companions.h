#pragma once
// The files a fuzzed mesh may refer to, written once next to it in the scratch folder: a material
// library "m.mtl" (one textured and one plain material) and its texture "t.png". Seeds name them
// (mtllib m.mtl, comment TextureFile t.png, a glTF image uri), so the material and texture paths of
// the readers are reached without the input naming files elsewhere on the machine.
#include <fstream>

#include "core/image.h"
#include "fuzz_common.h"
#include "io/image_codec.h"

namespace u3d::fuzz {

inline void write_mesh_companions() {
  static const bool written = [] {
    std::ofstream(scratch_dir() / "m.mtl") << "newmtl textured\nKd 1 1 1\nmap_Kd t.png\n"
                                              "newmtl red\nKd 1 0 0\nd 0.5\n";
    Image texture(4, 4, 3);
    for (size_t i = 0; i < texture.data.size(); ++i) texture.data[i] = float(i % 7) / 6.f;
    auto png = encode_png(texture, "fuzz texture");
    write_scratch_file("t.png", png.data(), png.size());
    return true;
  }();
  (void)written;
}

}  // namespace u3d::fuzz
