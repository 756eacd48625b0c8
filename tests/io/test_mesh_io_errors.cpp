// Format-independent failure handling of read_mesh/write_mesh.
#include <gtest/gtest.h>

#include <limits>

#include "core/error.h"
#include "io/image_codec.h"
#include "io/mesh_io.h"
#include "io_test_util.h"

namespace fs = std::filesystem;
using namespace u3d;
using namespace u3d::test;

namespace {

void expect_error_containing(const std::function<void()>& action, const std::string& expected) {
  try {
    action();
    ADD_FAILURE() << "no error; expected one containing '" << expected << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(MeshIo, MissingFileAndUnknownExtension) {
  fs::path dir = scratch_dir();
  for (const char* name : {"none.obj", "none.ply", "none.glb", "none.gltf"})
    expect_error_containing([&] { read_mesh(dir / name); }, "mesh file not found: " + (dir / name).string());
  write_file(dir / "mesh.stl", "solid x\nendsolid x\n");
  expect_error_containing([&] { read_mesh(dir / "mesh.stl"); }, "unsupported mesh file extension '.stl'");
  expect_error_containing([&] { write_mesh(colored_tetrahedron(), dir / "out.stl"); }, "unsupported output mesh extension");
  expect_error_containing([&] { write_mesh(colored_tetrahedron(), dir / "out.gltf"); }, "use .glb");
  expect_error_containing([&] { read_mesh(dir); }, "expected a mesh file");
}

TEST(MeshIo, UppercaseExtensionsWork) {
  fs::path dir = scratch_dir();
  write_mesh(colored_tetrahedron(), dir / "UPPER.PLY");
  EXPECT_EQ(read_mesh(dir / "UPPER.PLY").vertex_count(), 4u);
}

TEST(MeshIo, InvalidMeshesAreNotWritten) {
  fs::path dir = scratch_dir();
  Mesh nan_mesh = colored_tetrahedron();
  nan_mesh.positions[2].y() = std::numeric_limits<float>::quiet_NaN();
  Mesh bad_index = colored_tetrahedron();
  bad_index.faces[0][1] = 7;
  for (const char* ext : {".glb", ".obj", ".ply"}) {
    expect_error_containing([&] { write_mesh(Mesh{}, dir / (std::string("empty") + ext)); }, "no vertices");
    expect_error_containing([&] { write_mesh(nan_mesh, dir / (std::string("nan") + ext)); }, "NaN");
    expect_error_containing([&] { write_mesh(bad_index, dir / (std::string("index") + ext)); }, "references vertex 7");
  }
  EXPECT_EQ(file_count(dir), 0u);
}

TEST(MeshIo, UnwritableOutputFolderLeavesNoFile) {
  fs::path dir = scratch_dir();
  Mesh mesh = two_material_quads();
  for (const char* name : {"a.glb", "a.obj", "a.ply"}) {
    expect_error_containing([&] { write_mesh(mesh, dir / "missing_folder" / name); }, "does not exist");
    // /proc accepts no new files, even for root (for whom permission bits do not apply).
    EXPECT_THROW(write_mesh(mesh, fs::path("/proc") / name), Error);
    EXPECT_FALSE(fs::exists(fs::path("/proc") / name));
  }
  if (::geteuid() != 0) {
    fs::path locked = dir / "locked";
    fs::create_directory(locked);
    fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
    for (const char* name : {"a.glb", "a.obj", "a.ply"})
      expect_error_containing([&] { write_mesh(mesh, locked / name); }, "not writable");
    fs::permissions(locked, fs::perms::owner_all);
    EXPECT_EQ(file_count(locked), 0u);
  }
  EXPECT_EQ(file_count(dir), 0u + (::geteuid() != 0));
}

// Texture bytes with the DICOM signature went to GDCM, which aborted the process (found by fuzz_image);
// only PNG and JPEG bytes are decoded now.
TEST(MeshIo, EmbeddedDicomBytesAreAnErrorNotAnAbort) {
  const std::string bytes = std::string(128, '\xa7') + "DICM" + '\xa4';
  try {
    decode_image(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "image 0");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot decode image 0: not a PNG or JPEG image");
  }
}

// An OBJ's material library and a glTF's buffer or image URIs name other files; a name that is a folder
// or a device is refused before it is read (a folder read as an empty library before, and /dev/zero
// would have been read until memory ran out; found while fuzzing).
TEST(MeshIo, CompanionFilesMustBeRegularFiles) {
  fs::path dir = scratch_dir();
  fs::create_directory(dir / "lib.mtl");
  write_file(dir / "tri.obj", "mtllib lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
  expect_error_containing([&] { read_mesh(dir / "tri.obj"); }, "lib.mtl is a folder or device, not a file");
  fs::create_directory(dir / "tri.bin");
  write_file(dir / "tri.gltf",
             R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"tri.bin"}]})");
  expect_error_containing([&] { read_mesh(dir / "tri.gltf"); }, "tri.bin is a folder or device, not a file");
  fs::create_symlink("/dev/zero", dir / "zero.bin");
  write_file(dir / "zero.gltf",
             R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"zero.bin"}]})");
  expect_error_containing([&] { read_mesh(dir / "zero.gltf"); }, "zero.bin is a folder or device, not a file");
}
