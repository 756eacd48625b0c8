#pragma once
// Shared helpers for the mesh I/O tests: a scratch folder per test and small generated meshes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/mesh.h"
#include "core/temp_dir.h"

namespace u3d::test {

// A fresh empty folder named after the running test.
inline std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return u3d::testing::fresh_temp_dir("io_" + std::string(info->test_suite_name()) + "." + info->name());
}

inline void write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline size_t file_count(const std::filesystem::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

// Closed tetrahedron with outward counter-clockwise faces and distinct vertex colours whose
// channels are multiples of 1/255 (so 8-bit formats keep them exactly).
inline Mesh colored_tetrahedron() {
  Mesh m;
  m.positions = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  m.colors = {{1.f, 0.f, 0.f}, {0.f, 128 / 255.f, 0.f}, {0.f, 0.f, 1.f}, {10 / 255.f, 200 / 255.f, 1.f}};
  return m;
}

// Image whose pixels are multiples of 1/255 and differ everywhere, so orientation errors show.
inline Image gradient_texture(int width, int height, int channels, int seed) {
  Image im(width, height, channels);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c) im.at(x, y, c) = float((x * 37 + y * 71 + c * 13 + seed * 29) % 256) / 255.f;
  return im;
}

// Two quads side by side (4 triangles), one textured material per quad; the shared edge has the same
// UVs on both sides so nothing needs splitting.
inline Mesh two_material_quads() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0}};
  m.uvs = {{0.f, 0.f}, {0.5f, 0.f}, {1.f, 0.f}, {0.f, 1.f}, {0.5f, 1.f}, {1.f, 0.75f}};
  m.faces = {{0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4}};
  m.face_material = {0, 0, 1, 1};
  m.materials.push_back(Material{"left", Vec4f(1.f, 1.f, 1.f, 1.f), gradient_texture(8, 4, 3, 1)});
  m.materials.push_back(Material{"right", Vec4f(0.5f, 0.25f, 1.f, 1.f), gradient_texture(4, 6, 3, 2)});
  return m;
}

inline void expect_same_geometry(const Mesh& a, const Mesh& b, float tolerance = 0.f) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (size_t i = 0; i < a.positions.size(); ++i)
    EXPECT_LE((a.positions[i] - b.positions[i]).cwiseAbs().maxCoeff(), tolerance) << "vertex " << i;
  ASSERT_EQ(a.faces.size(), b.faces.size());
  for (size_t f = 0; f < a.faces.size(); ++f) EXPECT_EQ(a.faces[f], b.faces[f]) << "face " << f;
}

inline void expect_same_colors(const Mesh& a, const Mesh& b, float tolerance) {
  ASSERT_EQ(a.colors.size(), b.colors.size());
  for (size_t i = 0; i < a.colors.size(); ++i)
    EXPECT_LE((a.colors[i] - b.colors[i]).cwiseAbs().maxCoeff(), tolerance) << "colour of vertex " << i;
}

inline void expect_same_uvs(const Mesh& a, const Mesh& b, float tolerance) {
  ASSERT_EQ(a.uvs.size(), b.uvs.size());
  for (size_t i = 0; i < a.uvs.size(); ++i)
    EXPECT_LE((a.uvs[i] - b.uvs[i]).cwiseAbs().maxCoeff(), tolerance) << "UV of vertex " << i;
}

inline void expect_same_image(const Image& a, const Image& b, float tolerance) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.channels, b.channels);
  float worst = 0.f;
  for (size_t i = 0; i < a.data.size(); ++i) worst = std::max(worst, std::abs(a.data[i] - b.data[i]));
  EXPECT_LE(worst, tolerance);
}

}  // namespace u3d::test
