#include <gtest/gtest.h>

#include <cstring>

#include "core/error.h"
#include "io/mesh_io.h"
#include "io_test_util.h"

namespace fs = std::filesystem;
using namespace u3d;
using namespace u3d::test;

TEST(Ply, BinaryRoundTripKeepsPositionsFacesColorsUvsAndTexture) {
  fs::path dir = scratch_dir();
  Mesh mesh = colored_tetrahedron();
  mesh.uvs = {{0.f, 0.f}, {1.f, 0.f}, {0.f, 1.f}, {0.3f, 0.7f}};
  mesh.materials.push_back(Material{"tex", Vec4f::Ones(), gradient_texture(5, 3, 4, 3)});
  write_mesh(mesh, dir / "tet.ply");
  EXPECT_TRUE(fs::exists(dir / "tet_texture.png"));
  EXPECT_EQ(read_file(dir / "tet.ply").rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  Mesh back = read_mesh(dir / "tet.ply");
  expect_same_geometry(mesh, back);
  expect_same_colors(mesh, back, 1e-6f);  // colours are multiples of 1/255: uchar keeps them
  expect_same_uvs(mesh, back, 0.f);
  ASSERT_EQ(back.materials.size(), 1u);
  expect_same_image(mesh.materials[0].texture, back.materials[0].texture, 1e-6f);
}

TEST(Ply, ReadsAsciiWithFloatColorsPolygonsAndExtraElements) {
  fs::path dir = scratch_dir();
  write_file(dir / "quad.ply",
             "ply\r\nformat ascii 1.0\ncomment a quad\n"
             "element vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
             "property float nx\nproperty float red\nproperty float green\nproperty float blue\n"
             "element face 1\nproperty list uchar uint vertex_index\nproperty uchar flags\n"
             "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
             "0 0 0 1 0.25 0.5 1\n1 0 0 1 0 0 0\n1 1 0 1 1 1 1\n0 1 0 1 0.1 0.2 0.3\n"
             "4 0 1 2 3 7\n0 1\n");
  Mesh mesh = read_mesh(dir / "quad.ply");
  ASSERT_EQ(mesh.vertex_count(), 4u);
  ASSERT_EQ(mesh.face_count(), 2u);
  EXPECT_EQ(mesh.faces[0], Vec3i(0, 1, 2));
  EXPECT_EQ(mesh.faces[1], Vec3i(0, 2, 3));
  EXPECT_EQ(mesh.positions[2], Vec3f(1, 1, 0));
  EXPECT_TRUE(mesh.colors[0].isApprox(Vec3f(0.25f, 0.5f, 1.f)));
  EXPECT_TRUE(mesh.colors[3].isApprox(Vec3f(0.1f, 0.2f, 0.3f)));
  EXPECT_TRUE(mesh.uvs.empty());
}

TEST(Ply, ReadsBigEndianBinaryWithUcharColors) {
  fs::path dir = scratch_dir();
  std::string data =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  auto put_float = [&](float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    for (int s = 24; s >= 0; s -= 8) data += char((bits >> s) & 0xff);
  };
  float xyz[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}};
  for (int v = 0; v < 3; ++v) {
    for (float c : xyz[v]) put_float(c);
    data += char(v * 100);
    data += char(255);
    data += char(0);
  }
  data += char(3);
  for (int i : {0, 1, 2}) data += std::string{0, 0, 0, char(i)};
  write_file(dir / "be.ply", data);
  Mesh mesh = read_mesh(dir / "be.ply");
  ASSERT_EQ(mesh.vertex_count(), 3u);
  EXPECT_EQ(mesh.positions[2], Vec3f(0, 3, 0));
  EXPECT_EQ(mesh.faces[0], Vec3i(0, 1, 2));
  EXPECT_FLOAT_EQ(mesh.colors[2][0], 200 / 255.f);
  EXPECT_FLOAT_EQ(mesh.colors[2][1], 1.f);
}

TEST(Ply, CorruptAndTruncatedFilesGiveErrors) {
  fs::path dir = scratch_dir();
  write_mesh(colored_tetrahedron(), dir / "good.ply");
  std::string good = read_file(dir / "good.ply");
  write_file(dir / "truncated.ply", good.substr(0, good.size() - 7));
  write_file(dir / "noheader.ply", good.substr(0, 40));
  write_file(dir / "magic.ply", "plx\n" + good.substr(4));
  std::string huge = good;
  huge.replace(huge.find("element vertex 4"), 16, "element vertex 999999999");
  write_file(dir / "huge.ply", huge);
  write_file(dir / "index.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n");
  write_file(dir / "negative.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n");
  // A face claiming 2^31 - 16 vertices in a 100-byte file: an error, not an 8 GB allocation.
  std::string huge_face = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n";
  huge_face += std::string(36, '\0') + std::string("\xf0\xff\xff\x7f", 4) + std::string(12, '\0');
  write_file(dir / "huge_face.ply", huge_face);
  write_file(dir / "text.ply",
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
             "end_header\n0 zero 0\n");
  const std::pair<const char*, const char*> cases[] = {
      {"truncated.ply", "unexpected end of data"}, {"noheader.ply", "no end_header"},
      {"magic.ply", "not a PLY file"},            {"huge.ply", "too short"},
      {"index.ply", "references vertex 9"},       {"text.ply", "'zero' is not a number"},
      {"negative.ply", "vertex index -1 is out of range"}, {"huge_face.ply", "claims 2147483632 vertices"}};  // an integer, printed as one
  for (const auto& [name, expected] : cases) {
    try {
      read_mesh(dir / name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << name << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << "the message names the file: " << e.what();
    }
  }
}
