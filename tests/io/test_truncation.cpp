// Every prefix of a valid file is either read as a valid mesh or rejected with u3d::Error: no crash,
// no other exception type, no giant allocation.
#include <gtest/gtest.h>

#include "core/error.h"
#include "io/mesh_io.h"
#include "io_test_util.h"

namespace fs = std::filesystem;
using namespace u3d;
using namespace u3d::test;

namespace {

void check_every_prefix(const fs::path& dir, const std::string& name, const Mesh& mesh) {
  write_mesh(mesh, dir / name);
  std::string bytes = read_file(dir / name);
  fs::path cut = dir / ("cut_" + name);
  size_t accepted = 0;
  for (size_t n = 0; n < bytes.size(); ++n) {
    write_file(cut, bytes.substr(0, n));
    try {
      read_mesh(cut);
      ++accepted;
    } catch (const Error&) {
    } catch (const std::exception& e) {
      ADD_FAILURE() << name << " cut to " << n << " bytes threw a non-Error exception: " << e.what();
    }
  }
  // Text formats may legitimately end at a line break; binary ones never before their last byte.
  if (fs::path(name).extension() != ".obj") {
    EXPECT_EQ(accepted, 0u) << name;
  }
}

}  // namespace

TEST(Truncation, EveryPrefixIsReadOrRejectedWithError) {
  fs::path dir = scratch_dir();
  Mesh mesh = colored_tetrahedron();
  mesh.uvs = {{0.f, 0.f}, {1.f, 0.f}, {0.f, 1.f}, {0.5f, 0.5f}};
  check_every_prefix(dir, "tet.ply", mesh);
  check_every_prefix(dir, "tet.glb", mesh);
  check_every_prefix(dir, "tet.obj", mesh);
}
