// The GLB files we write must pass the Khronos glTF validator (tools/validate_gltf.mjs) with no errors.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "io/mesh_io.h"
#include "io_test_util.h"

namespace fs = std::filesystem;
using namespace u3d;
using namespace u3d::test;

namespace {

// Exit status of the validator script on `file`; its report goes to the test log.
int validate(const fs::path& file) {
  std::string command = "node \"" UNIQUE3D_SOURCE_DIR "/tools/validate_gltf.mjs\" \"" + file.string() + "\"";
  int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Empty when the validator can run, else why not: the tests then skip with that reason (the script
// itself exits 2 both when it is not installed and when a file cannot be read).
std::string validator_missing() {
  if (std::system("command -v node > /dev/null 2>&1") != 0) return "node is not installed";
  if (!fs::exists(UNIQUE3D_SOURCE_DIR "/tools/node_modules/gltf-validator/package.json"))
    return "the npm gltf-validator is not in tools/node_modules (scripts/install_deps.sh installs it)";
  return "";
}

}  // namespace

TEST(GltfValidator, WrittenGlbFilesHaveNoErrors) {
  if (const std::string why = validator_missing(); !why.empty())
    GTEST_SKIP() << why << ": cannot run the glTF validator";
  fs::path dir = scratch_dir();

  Mesh colored = colored_tetrahedron();
  write_mesh(colored, dir / "coloured.glb");
  EXPECT_EQ(validate(dir / "coloured.glb"), 0);

  write_mesh(two_material_quads(), dir / "textured.glb");
  EXPECT_EQ(validate(dir / "textured.glb"), 0);
  write_mesh(two_material_quads(), dir / "textured_jpeg.glb", {TextureFormat::Jpeg});
  EXPECT_EQ(validate(dir / "textured_jpeg.glb"), 0);

  // Colours + UVs + an RGBA texture + a translucent untextured material + an isolated vertex (whose
  // normal is undefined) + a degenerate face.
  Mesh mixed = two_material_quads();
  mixed.colors.assign(mixed.vertex_count(), Vec3f(0.2f, 0.4f, 0.6f));
  mixed.materials[0].texture = gradient_texture(3, 3, 4, 5);
  mixed.materials[1].texture = Image();
  mixed.materials[1].base_color[3] = 0.5f;
  mixed.positions.push_back(Vec3f(5, 5, 5));
  mixed.colors.push_back(Vec3f(1, 1, 1));
  mixed.uvs.push_back(Vec2f(0, 0));
  mixed.faces.push_back(Vec3i(0, 0, 1));
  mixed.face_material.push_back(1);
  write_mesh(mixed, dir / "mixed.glb");
  EXPECT_EQ(validate(dir / "mixed.glb"), 0);

  // A real object with UV seams (texture shrunk to keep the test quick).
  Mesh avocado = read_mesh(fs::path(UNIQUE3D_TEST_DATA) / "objects" / "avocado" / "avocado.obj");
  avocado.materials[0].texture = resize_image(avocado.materials[0].texture, 128, 128);
  write_mesh(avocado, dir / "avocado.glb");
  EXPECT_EQ(validate(dir / "avocado.glb"), 0);
}

// The check above only means something if the validator rejects broken files: exit 1, a validation
// error (2 would be a file it could not read).
TEST(GltfValidator, RejectsABrokenFile) {
  if (const std::string why = validator_missing(); !why.empty())
    GTEST_SKIP() << why << ": cannot run the glTF validator";
  fs::path dir = scratch_dir();
  write_mesh(colored_tetrahedron(), dir / "good.glb");
  std::string bytes = read_file(dir / "good.glb");
  write_file(dir / "broken.glb", bytes.substr(0, bytes.size() - 16));
  EXPECT_EQ(validate(dir / "broken.glb"), 1);
}
