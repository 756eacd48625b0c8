#include <gtest/gtest.h>

#include "core/error.h"
#include "io/mesh_io.h"
#include "io_test_util.h"

namespace fs = std::filesystem;
using namespace u3d;
using namespace u3d::test;

TEST(Obj, ColoredMeshRoundTripIsExact) {
  fs::path dir = scratch_dir();
  Mesh mesh = colored_tetrahedron();
  mesh.positions[1] = Vec3f(0.1f, -1e-7f, 3.14159265f);  // needs all float digits
  mesh.colors[2] = Vec3f(0.123456789f, 0.5f, 1.f / 3.f);
  write_mesh(mesh, dir / "tet.obj");
  EXPECT_FALSE(fs::exists(dir / "tet.mtl")) << "no materials, no .mtl";
  Mesh back = read_mesh(dir / "tet.obj");
  expect_same_geometry(mesh, back);
  expect_same_colors(mesh, back, 0.f);
  EXPECT_TRUE(back.uvs.empty());
  EXPECT_TRUE(back.materials.empty());
}

TEST(Obj, TwoTexturedMaterialsRoundTrip) {
  fs::path dir = scratch_dir();
  Mesh mesh = two_material_quads();
  write_mesh(mesh, dir / "quads.obj");
  EXPECT_TRUE(fs::exists(dir / "quads.mtl"));
  EXPECT_TRUE(fs::exists(dir / "quads_texture0.png"));
  EXPECT_TRUE(fs::exists(dir / "quads_texture1.png"));
  Mesh back = read_mesh(dir / "quads.obj");
  expect_same_geometry(mesh, back);
  expect_same_uvs(mesh, back, 0.f);
  ASSERT_EQ(back.materials.size(), 2u);
  EXPECT_EQ(back.face_material, mesh.face_material);
  for (int m = 0; m < 2; ++m) {
    EXPECT_EQ(back.materials[m].name, mesh.materials[m].name);
    EXPECT_TRUE(back.materials[m].base_color.isApprox(mesh.materials[m].base_color));
    expect_same_image(mesh.materials[m].texture, back.materials[m].texture, 1e-6f);
  }
}

TEST(Obj, ReadsPolygonsNegativeIndicesSeamsAndVertexColors) {
  fs::path dir = scratch_dir();
  save_image(gradient_texture(4, 4, 3, 7), dir / "wood.png");
  save_image(gradient_texture(2, 2, 3, 9), dir / "metal tex.png");
  write_file(dir / "lib.mtl",
             "newmtl wood\nKd 0.5 0.25 1\nmap_Kd -s 1 1 1 wood.png\n"
             "newmtl metal\nKd 1 1 1\nd 0.5\nmap_Kd metal tex.png\n");
  write_file(dir / "shape.obj",
             "# quad and triangle sharing an edge, with a UV seam at vertex 2\n"
             "mtllib lib.mtl\n"
             "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\nv 2 0 0 0.5 0.5 0.5\n"
             "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.25 0.75\n"
             "vn 0 0 1\n"
             "usemtl wood\n"
             "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
             "usemtl metal\n"
             "f -4/-4/-1 -1/-1/-1 -3/-1/-1\n");
  Mesh mesh = read_mesh(dir / "shape.obj");
  ASSERT_EQ(mesh.face_count(), 3u);  // quad fans into two triangles
  EXPECT_EQ(mesh.faces[0], Vec3i(0, 1, 2));
  EXPECT_EQ(mesh.faces[1], Vec3i(0, 2, 3));
  // Second face: vertex 2 (index 1) with vt 2 (same as before), vertex 5 with vt 5, vertex 3 with vt 5:
  // vertex 3 was used with vt 3 already, so it is split into a new vertex 5.
  EXPECT_EQ(mesh.faces[2], Vec3i(1, 4, 5));
  ASSERT_EQ(mesh.vertex_count(), 6u);
  EXPECT_EQ(mesh.positions[5], Vec3f(1, 1, 0));
  EXPECT_EQ(mesh.uvs[5], Vec2f(0.25f, 0.75f));
  EXPECT_EQ(mesh.uvs[2], Vec2f(1.f, 1.f));
  EXPECT_EQ(mesh.colors[5], Vec3f(0, 0, 1)) << "split vertices keep their colour";
  EXPECT_EQ(mesh.colors[4], Vec3f(0.5f, 0.5f, 0.5f));
  ASSERT_EQ(mesh.materials.size(), 2u);
  EXPECT_EQ(mesh.face_material, (std::vector<int>{0, 0, 1}));
  EXPECT_EQ(mesh.materials[0].name, "wood");
  EXPECT_TRUE(mesh.materials[0].base_color.isApprox(Vec4f(0.5f, 0.25f, 1.f, 1.f)));
  EXPECT_EQ(mesh.materials[0].texture.width, 4);
  EXPECT_FLOAT_EQ(mesh.materials[1].base_color[3], 0.5f);
  EXPECT_EQ(mesh.materials[1].texture.width, 2) << "texture file names may contain spaces";
}

TEST(Obj, FacesBeforeUsemtlGetADefaultMaterial) {
  fs::path dir = scratch_dir();
  write_file(dir / "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl unknown_name\nf 1 3 2\n");
  Mesh mesh = read_mesh(dir / "m.obj");
  ASSERT_EQ(mesh.materials.size(), 2u);
  EXPECT_EQ(mesh.materials[0].name, "unknown_name");
  EXPECT_EQ(mesh.materials[1].name, "default");
  EXPECT_EQ(mesh.face_material, (std::vector<int>{1, 0}));
}

TEST(Obj, BadFilesGiveErrorsNamingTheProblem) {
  fs::path dir = scratch_dir();
  auto expect_error = [&](const std::string& name, const std::string& text, const std::string& expected) {
    write_file(dir / name, text);
    try {
      read_mesh(dir / name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << name << ": " << e.what();
    }
  };
  expect_error("number.obj", "v 0 0 0\nv 1 abc 0\n", "number.obj:2: 'abc' is not a number");
  expect_error("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "out of range");
  expect_error("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "bad vertex index");
  expect_error("short.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "at least three vertices");
  expect_error("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "NaN");
  expect_error("empty.obj", "# nothing\n", "no vertices");
  expect_error("points.obj", "v 0 0 0\nv 1 0 0\n", "no faces");
  expect_error("binary.obj", std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16), "no vertices");
  expect_error("nomtl.obj", "mtllib missing.mtl\nv 0 0 0\n", "missing.mtl does not exist");
  write_file(dir / "notex.mtl", "newmtl a\nmap_Kd gone.png\n");
  expect_error("notex.obj", "mtllib notex.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n", "gone.png");
  // A material colour that is not a finite number is named where it stands, not when it is written.
  write_file(dir / "nan.mtl", "newmtl a\nKd 0.5 nan 0.5\n");
  expect_error("nankd.obj", "mtllib nan.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n", "nan.mtl:2: bad Kd value 'nan'");
  write_file(dir / "inf.mtl", "newmtl a\nd inf\n");
  expect_error("infd.obj", "mtllib inf.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n", "inf.mtl:2: bad d value");
}

TEST(Obj, FailedTextureLeavesNoFilesBehind) {
  fs::path dir = scratch_dir();
  Mesh mesh = two_material_quads();
  mesh.materials[1].texture.data[5] = std::numeric_limits<float>::quiet_NaN();  // second texture fails
  EXPECT_THROW(write_mesh(mesh, dir / "bad.obj"), Error);
  EXPECT_EQ(file_count(dir), 0u) << "the first texture must be removed again";
}
