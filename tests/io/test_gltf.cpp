#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <regex>

#include "core/color_space.h"
#include "core/error.h"
#include "io/mesh_io.h"
#include "io/tinygltf.h"
#include "io_test_util.h"

namespace fs = std::filesystem;
using namespace u3d;
using namespace u3d::test;

TEST(Glb, ColoredRoundTripConvertsColorsThroughLinearAndBack) {
  fs::path dir = scratch_dir();
  Mesh mesh = colored_tetrahedron();
  write_mesh(mesh, dir / "tet.glb");
  std::string bytes = read_file(dir / "tet.glb");
  ASSERT_GE(bytes.size(), 20u);
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
  Mesh back = read_mesh(dir / "tet.glb");
  expect_same_geometry(mesh, back);
  expect_same_colors(mesh, back, 1e-5f);
  EXPECT_TRUE(back.uvs.empty());
  EXPECT_TRUE(back.materials.empty()) << "the plain material the writer adds is not a real one";
}

// The file must hold LINEAR colours: read the COLOR_0 accessor directly, bypassing our reader.
TEST(Glb, StoresLinearVertexColorsAndFlippedUvs) {
  fs::path dir = scratch_dir();
  Mesh mesh = colored_tetrahedron();
  mesh.uvs = {{0.f, 0.f}, {1.f, 0.25f}, {0.f, 1.f}, {0.5f, 0.5f}};
  write_mesh(mesh, dir / "tet.glb");
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, (dir / "tet.glb").string())) << err;
  const auto& primitive = model.meshes.at(0).primitives.at(0);
  auto floats = [&](const char* attribute) {
    const auto& accessor = model.accessors.at(primitive.attributes.at(attribute));
    EXPECT_EQ(accessor.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
    const auto& view = model.bufferViews.at(accessor.bufferView);
    std::vector<float> out(accessor.count * tinygltf::GetNumComponentsInType(accessor.type));
    std::memcpy(out.data(), model.buffers[0].data.data() + view.byteOffset + accessor.byteOffset, out.size() * 4);
    return out;
  };
  std::vector<float> colors = floats("COLOR_0");
  ASSERT_EQ(colors.size(), 12u);
  EXPECT_NEAR(colors[4], srgb_to_linear(128 / 255.f), 1e-7f);
  EXPECT_NEAR(colors[4], 0.2158605f, 1e-6f);  // the exact sRGB EOTF, not a 2.2 gamma (0.2195)
  EXPECT_FLOAT_EQ(colors[0], 1.f);
  std::vector<float> uvs = floats("TEXCOORD_0");
  EXPECT_FLOAT_EQ(uvs[2], 1.f);
  EXPECT_FLOAT_EQ(uvs[3], 0.75f);  // v flipped: glTF's origin is the top-left
  std::vector<float> normals = floats("NORMAL");
  for (size_t i = 0; i < normals.size(); i += 3)
    EXPECT_NEAR(std::sqrt(normals[i] * normals[i] + normals[i + 1] * normals[i + 1] + normals[i + 2] * normals[i + 2]), 1.f, 1e-6f);
  const auto& material = model.materials.at(0);
  EXPECT_EQ(material.pbrMetallicRoughness.metallicFactor, 0.0);
  EXPECT_EQ(material.pbrMetallicRoughness.roughnessFactor, 1.0);
  EXPECT_FALSE(material.doubleSided);
}

TEST(Glb, TexturedTwoMaterialRoundTrip) {
  fs::path dir = scratch_dir();
  Mesh mesh = two_material_quads();
  write_mesh(mesh, dir / "quads.glb");
  EXPECT_EQ(file_count(dir), 1u) << "textures are embedded";
  Mesh back = read_mesh(dir / "quads.glb");
  expect_same_geometry(mesh, back);
  expect_same_uvs(mesh, back, 1e-7f);
  EXPECT_TRUE(back.colors.empty());
  ASSERT_EQ(back.materials.size(), 2u);
  EXPECT_EQ(back.face_material, mesh.face_material);
  for (int m = 0; m < 2; ++m) {
    EXPECT_EQ(back.materials[m].name, mesh.materials[m].name);
    EXPECT_LE((back.materials[m].base_color - mesh.materials[m].base_color).cwiseAbs().maxCoeff(), 1e-5f);
    expect_same_image(mesh.materials[m].texture, back.materials[m].texture, 1e-6f);
  }
}

namespace {

template <typename T>
int append_buffer(tinygltf::Model& model, const std::vector<T>& values) {
  auto& data = model.buffers[0].data;
  data.resize((data.size() + 3) / 4 * 4);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = values.size() * sizeof(T);
  data.resize(data.size() + view.byteLength);
  std::memcpy(data.data() + view.byteOffset, values.data(), view.byteLength);
  model.bufferViews.push_back(view);
  return int(model.bufferViews.size()) - 1;
}

int add_accessor(tinygltf::Model& model, int view, int component, int type, size_t count, bool normalized = false) {
  tinygltf::Accessor accessor;
  accessor.bufferView = view;
  accessor.componentType = component;
  accessor.type = type;
  accessor.count = count;
  accessor.normalized = normalized;
  model.accessors.push_back(accessor);
  return int(model.accessors.size()) - 1;
}

// One triangle (0,0,0) (1,0,0) (0,1,0), seen counter-clockwise from +Z, with ubyte vec4 colours and
// ushort indices, instanced by several nodes.
tinygltf::Model instanced_triangle_model() {
  tinygltf::Model model;
  model.buffers.resize(1);
  int positions = add_accessor(model, append_buffer(model, std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}),
                               TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3);
  model.accessors[positions].minValues = {0, 0, 0};
  model.accessors[positions].maxValues = {1, 1, 0};
  int indices = add_accessor(model, append_buffer(model, std::vector<uint16_t>{0, 1, 2}),
                             TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, 3);
  int colors = add_accessor(model, append_buffer(model, std::vector<uint8_t>{255, 128, 0, 255, 0, 0, 0, 255, 0, 0, 255, 255}),
                            TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4, 3, true);
  tinygltf::Primitive primitive;
  primitive.attributes = {{"POSITION", positions}, {"COLOR_0", colors}};
  primitive.indices = indices;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  model.meshes.resize(1);
  model.meshes[0].primitives.push_back(primitive);

  model.nodes.resize(4);
  model.nodes[0].translation = {10, 0, 0};  // parent: T * S, child: R (90 degrees about +Z)
  model.nodes[0].scale = {2, 2, 2};
  model.nodes[0].children = {1};
  model.nodes[1].rotation = {0, 0, std::sin(M_PI / 4), std::cos(M_PI / 4)};
  model.nodes[1].mesh = 0;
  model.nodes[2].matrix = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1};  // mirror x, then z += 5
  model.nodes[2].mesh = 0;
  model.nodes[3].mesh = 0;  // only in the second scene: must be ignored
  model.scenes.resize(2);
  model.scenes[0].nodes = {0, 2};
  model.scenes[1].nodes = {3};
  model.defaultScene = 0;
  model.asset.version = "2.0";
  return model;
}

}  // namespace

TEST(Glb, NodeTransformsOfTheDefaultSceneAreApplied) {
  fs::path dir = scratch_dir();
  tinygltf::Model model = instanced_triangle_model();
  tinygltf::TinyGLTF writer;
  ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, (dir / "nodes.glb").string(), true, true, false, true));
  Mesh mesh = read_mesh(dir / "nodes.glb");
  ASSERT_EQ(mesh.vertex_count(), 6u);
  ASSERT_EQ(mesh.face_count(), 2u);
  const Vec3f expected[6] = {{10, 0, 0}, {10, 2, 0}, {8, 0, 0}, {0, 0, 5}, {-1, 0, 5}, {0, 1, 5}};
  for (int i = 0; i < 6; ++i) EXPECT_LE((mesh.positions[i] - expected[i]).norm(), 1e-5f) << "vertex " << i;
  // Both instances still face +Z: the mirrored one had its winding restored.
  for (const Vec3f& n : face_normals(mesh.positions, mesh.faces)) EXPECT_GT(n.z(), 0.99f);
  // Normalized ubyte linear colours become sRGB.
  ASSERT_EQ(mesh.colors.size(), 6u);
  EXPECT_NEAR(mesh.colors[0][1], linear_to_srgb(128 / 255.f), 1e-6f);
  EXPECT_NEAR(mesh.colors[0][1], 0.7372f, 1e-3f);
  EXPECT_LE((mesh.colors[2] - Vec3f(0, 0, 1)).cwiseAbs().maxCoeff(), 1e-6f);
}

TEST(Glb, CorruptFilesGiveErrors) {
  fs::path dir = scratch_dir();
  write_mesh(two_material_quads(), dir / "good.glb");
  std::string good = read_file(dir / "good.glb");
  write_file(dir / "truncated.glb", good.substr(0, good.size() - 40));
  write_file(dir / "garbage.glb", "glTF" + std::string(60, '\x07'));
  write_file(dir / "empty.glb", "");
  write_file(dir / "text.gltf", "{ this is not json");
  // buffers[0].byteLength 0 (spaces keep the JSON chunk's length): tinygltf throws out of its parser.
  std::smatch length;
  ASSERT_TRUE(std::regex_search(good, length, std::regex("\"buffers\":\\[\\{\"byteLength\":([0-9]+)")));
  std::string zero_length = good;
  zero_length.replace(size_t(length.position(1)), size_t(length.length(1)),
                      "0" + std::string(size_t(length.length(1)) - 1, ' '));
  write_file(dir / "zero_buffer.glb", zero_length);
  for (const char* name : {"truncated.glb", "garbage.glb", "empty.glb", "text.gltf", "zero_buffer.glb"}) {
    try {
      read_mesh(dir / name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

// An image stored in a buffer view that reaches past its 4-byte buffer: tinygltf passed the bytes on
// unchecked and the decoder read past the buffer (an ASan heap overflow, found by fuzz_gltf).
TEST(Gltf, ImageBufferViewPastItsBufferIsAnError) {
  fs::path dir = scratch_dir();
  write_file(dir / "overrun.gltf",
             R"({"asset":{"version":"2.0"},)"
             R"("buffers":[{"byteLength":4,"uri":"data:application/octet-stream;base64,AAAAAA=="}],)"
             R"("bufferViews":[{"buffer":0,"byteOffset":2,"byteLength":4000}],)"
             R"("images":[{"bufferView":0,"mimeType":"image/png"}]})");
  try {
    read_mesh(dir / "overrun.gltf");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("buffer view reaches past the end of its buffer"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("overrun.gltf"), std::string::npos) << e.what();
  }
}

// A .gltf with an external .bin and PNG, written by tinygltf rather than by us, so a UV flip that our
// writer and reader got wrong in the same way could not cancel out.
TEST(Gltf, ReadsExternalBufferAndTextureAndFlipsTexcoords) {
  fs::path dir = scratch_dir();
  tinygltf::Model model = instanced_triangle_model();
  model.scenes[0].nodes = {3};
  int uvs = add_accessor(model, append_buffer(model, std::vector<float>{0.25f, 0.1f, 1.f, 0.f, 0.f, 1.f}),
                         TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, 3);
  model.meshes[0].primitives[0].attributes["TEXCOORD_0"] = uvs;
  model.meshes[0].primitives[0].material = 0;
  save_image(gradient_texture(4, 2, 3, 4), dir / "albedo.png");
  tinygltf::Image image;
  image.uri = "albedo.png";
  model.images.push_back(image);
  tinygltf::Texture texture;
  texture.source = 0;
  model.textures.push_back(texture);
  tinygltf::Material material;
  material.name = "skin";
  material.pbrMetallicRoughness.baseColorFactor = {0.5, 1.0, 0.0, 1.0};
  material.pbrMetallicRoughness.baseColorTexture.index = 0;
  model.materials.push_back(material);
  model.buffers[0].uri = "tri.bin";
  tinygltf::TinyGLTF writer;
  ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, (dir / "tri.gltf").string(), false, false, true, false));
  ASSERT_TRUE(fs::exists(dir / "tri.bin"));

  Mesh mesh = read_mesh(dir / "tri.gltf");
  ASSERT_EQ(mesh.vertex_count(), 3u);
  EXPECT_EQ(mesh.positions[1], Vec3f(1, 0, 0));
  ASSERT_EQ(mesh.uvs.size(), 3u);
  EXPECT_NEAR(mesh.uvs[0].x(), 0.25f, 1e-7f);
  EXPECT_NEAR(mesh.uvs[0].y(), 0.9f, 1e-7f);
  EXPECT_NEAR(mesh.uvs[2].y(), 0.f, 1e-7f);
  ASSERT_EQ(mesh.materials.size(), 1u);
  EXPECT_EQ(mesh.materials[0].name, "skin");
  EXPECT_NEAR(mesh.materials[0].base_color[0], linear_to_srgb(0.5f), 1e-6f);
  expect_same_image(gradient_texture(4, 2, 3, 4), mesh.materials[0].texture, 1e-6f);

  fs::remove(dir / "albedo.png");
  EXPECT_THROW(read_mesh(dir / "tri.gltf"), Error) << "a missing texture image is an error";
}
