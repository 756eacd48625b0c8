// A real textured object (the glTF sample avocado, converted to OBJ; see its SOURCE.txt) through every
// format.
#include <gtest/gtest.h>

#include "io/mesh_io.h"
#include "io_test_util.h"

namespace fs = std::filesystem;
using namespace u3d;
using namespace u3d::test;

namespace {
const fs::path kAvocado = fs::path(UNIQUE3D_TEST_DATA) / "objects" / "avocado" / "avocado.obj";
}

TEST(RealObject, AvocadoObjSplitsSeamVerticesAndLoadsItsTexture) {
  Mesh mesh = read_mesh(kAvocado);
  // SOURCE.txt: 363 positions, 406 UVs, 682 triangles; the faces use 406 distinct (position, UV) pairs.
  EXPECT_EQ(mesh.vertex_count(), 406u);
  EXPECT_EQ(mesh.face_count(), 682u);
  ASSERT_EQ(mesh.materials.size(), 1u);
  EXPECT_EQ(mesh.materials[0].name, "mat0");
  EXPECT_EQ(mesh.materials[0].texture.width, 2048);
  EXPECT_TRUE(mesh.has_texture());
  BoundingBox box = bounding_box(mesh.positions);
  EXPECT_NEAR(box.max.y(), 0.0628f, 1e-4f);
  EXPECT_NEAR(box.min.x(), -0.0213f, 1e-4f);
}

TEST(RealObject, AvocadoSurvivesEveryFormat) {
  fs::path dir = scratch_dir();
  Mesh mesh = read_mesh(kAvocado);
  // Encoding the 2048x2048 texture as PNG costs about a second per format; a smaller copy keeps the
  // test quick and still exercises every texture path.
  mesh.materials[0].texture = resize_image(mesh.materials[0].texture, 256, 256);
  for (const char* name : {"avocado.glb", "avocado.obj", "avocado.ply"}) {
    write_mesh(mesh, dir / name);
    Mesh back = read_mesh(dir / name);
    expect_same_geometry(mesh, back);
    expect_same_uvs(mesh, back, 1e-7f);
    ASSERT_EQ(back.materials.size(), 1u) << name;
    // The JPEG texture is stored as 8-bit PNG: exact up to the 8-bit rounding of decoded values.
    expect_same_image(mesh.materials[0].texture, back.materials[0].texture, 0.5f / 255.f + 1e-6f);
  }
}
