// Texture baking: a sphere's views baked into a texture and rendered back with the project's renderer
// give the views again (closer than vertex colours), the texture sits the right way up for the mesh UV
// convention and for glTF (UV origin at the top-left of the image, read straight from the GLB bytes),
// and the GLB round trip keeps it; texels used is the share of texels baking fills.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/synthetic_views.h"
#include "geometry/icosphere.h"
#include "geometry/test_shapes.h"
#include "io/image_codec.h"
#include "io/mesh_io.h"
#include "isomer/texture_bake.h"
#include "render/render_view.h"
#include "render/texture_sampler.h"

namespace u3d {
namespace {

constexpr float kRadius = 0.6f;

// A colour of the surface point with unit normal n, different on every side and fast-varying.
Vec3f surface_color(const Vec3f& n) {
  return Vec3f(0.5f + 0.4f * n.x(), 0.5f + 0.3f * std::sin(9.f * n.y()), 0.5f + 0.4f * std::sin(7.f * n.z() + 1.f));
}

const ViewSet& views() {
  static const ViewSet v = testing::sphere_views(kRadius, 256, [](View, const Vec3f& n) { return surface_color(n); });
  return v;
}

// Mean absolute RGB difference over pixels both images cover.
double mean_error(const Image& a, const Image& b) {
  double sum = 0;
  size_t count = 0;
  for (size_t p = 0; p < a.pixel_count(); ++p) {
    if (a.data[p * 4 + 3] < 1.f || b.data[p * 4 + 3] < 1.f) continue;
    for (int c = 0; c < 3; ++c) sum += std::abs(a.data[p * 4 + c] - b.data[p * 4 + c]);
    count += 3;
  }
  return count ? sum / double(count) : 1.0;
}

double mean_view_error(const Mesh& mesh) {
  double sum = 0;
  for (View v : kAllViews) sum += mean_error(render_view(mesh, view_camera(v, 256)).rgb, views()[v].rgb);
  return sum / 4;
}

Mesh baked_sphere(TextureBakeReport* report = nullptr) {
  Mesh mesh = make_icosphere(5, kRadius);
  TextureBakeOptions options;
  options.atlas.texture_size = 1024;
  const TextureBakeReport r = bake_texture(mesh, views(), {}, options);
  if (report) *report = r;
  return mesh;
}

TEST(TextureBake, RendersBackTheViewsBetterThanVertexColours) {
  TextureBakeReport report;
  const Mesh textured = baked_sphere(&report);
  ASSERT_TRUE(textured.has_texture());
  EXPECT_FALSE(textured.has_colors());
  EXPECT_EQ(textured.materials[0].texture.width, 1024);
  EXPECT_GT(report.texels_covered, 0u);
  EXPECT_GT(report.texels_confident, report.texels_covered / 2);
  // Texels used: the texels baking fills, counted; the charts' gutters are not.
  EXPECT_DOUBLE_EQ(report.texel_efficiency, float(double(report.texels_covered) / (1024.0 * 1024.0)));
  std::printf("texels used: %.3f\n", report.texel_efficiency);
  EXPECT_GT(report.texel_efficiency, 0.55f);  // 0.60 at 1024 with 4-texel gutters; shelf packing used about 0.4
  Mesh vertex_colored = make_icosphere(5, kRadius);
  color_mesh(vertex_colored, views());
  const double texture_error = mean_view_error(textured), vertex_error = mean_view_error(vertex_colored);
  std::printf("mean view error: texture %.4f, vertex colours %.4f\n", texture_error, vertex_error);
  EXPECT_LT(texture_error, 0.02);
  EXPECT_LT(texture_error, vertex_error);
}

// Every atlas vertex's UV, looked up in the texture with the mesh convention, gives the colour of its
// surface point: a texture upside down or mirrored against its UVs fails this.
TEST(TextureBake, TextureIsTheRightWayUpForTheMeshUvs) {
  const Mesh textured = baked_sphere();
  double error = 0;
  for (size_t v = 0; v < textured.positions.size(); ++v)
    error += (sample_texture(textured.materials[0].texture, textured.uvs[v]).head<3>() -
              surface_color(textured.positions[v].normalized()))
                 .cwiseAbs()
                 .mean();
  EXPECT_LT(error / double(textured.positions.size()), 0.03);
}

// The written GLB read as glTF defines it (TEXCOORD_0 (0, 0) = the first pixel of the image, at its
// top-left), without the project's reader: what Blender and three.js see.
TEST(TextureBake, GlbTexturesFollowTheGltfUvConvention) {
  const Mesh textured = baked_sphere();
  const auto dir = testing::fresh_temp_dir("texture_glb");
  for (TextureFormat format : {TextureFormat::Png, TextureFormat::Jpeg}) {
    const auto path = dir / (format == TextureFormat::Png ? "png.glb" : "jpg.glb");
    write_mesh(textured, path, {format});
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string bytes = ss.str();
    uint32_t json_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    const nlohmann::json gltf = nlohmann::json::parse(bytes.substr(20, json_length));
    const char* bin = bytes.data() + 20 + json_length + 8;
    auto view_bytes = [&](int view) {
      const auto& bv = gltf["bufferViews"][view];
      return std::make_pair(bin + bv.value("byteOffset", size_t(0)), bv["byteLength"].get<size_t>());
    };
    const auto& image_json = gltf["images"][0];
    EXPECT_EQ(image_json["mimeType"], format == TextureFormat::Png ? "image/png" : "image/jpeg");
    const auto [image_data, image_size] = view_bytes(image_json["bufferView"]);
    const Image texture = decode_image(reinterpret_cast<const unsigned char*>(image_data), image_size, "GLB texture");
    const auto& primitive = gltf["meshes"][0]["primitives"][0];
    const auto& uv_accessor = gltf["accessors"][primitive["attributes"]["TEXCOORD_0"].get<int>()];
    const auto& pos_accessor = gltf["accessors"][primitive["attributes"]["POSITION"].get<int>()];
    const float* uvs = reinterpret_cast<const float*>(view_bytes(uv_accessor["bufferView"]).first);
    const float* positions = reinterpret_cast<const float*>(view_bytes(pos_accessor["bufferView"]).first);
    const size_t count = uv_accessor["count"];
    double error = 0;
    for (size_t v = 0; v < count; ++v) {
      const int x = std::min(int(uvs[2 * v] * texture.width), texture.width - 1);
      const int y = std::min(int(uvs[2 * v + 1] * texture.height), texture.height - 1);  // row 0 = top
      const Vec3f n = Vec3f(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]).normalized();
      error +=
          (Vec3f(texture.at(x, y, 0), texture.at(x, y, 1), texture.at(x, y, 2)) - surface_color(n)).cwiseAbs().mean();
    }
    EXPECT_LT(error / double(count), 0.04) << path;

    // And the project's own reader gives back what was written.
    const Mesh read = read_mesh(path);
    ASSERT_TRUE(read.has_texture());
    const Image before = render_view(textured, view_camera(View::Front, 256)).rgb;
    const Image after = render_view(read, view_camera(View::Front, 256)).rgb;
    EXPECT_LT(mean_error(before, after), format == TextureFormat::Png ? 0.003 : 0.01) << path;
  }
}

// A box, each triangle split into four at its edges' midpoints `levels` times (shared vertices).
Mesh subdivided_box(const Vec3f& lo, const Vec3f& hi, int levels) {
  Mesh m = test::box_mesh(lo, hi);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (const auto it = midpoint.find(key); it != midpoint.end()) return it->second;
      m.positions.push_back(0.5f * (m.positions[size_t(a)] + m.positions[size_t(b)]));
      return midpoint[key] = int(m.positions.size()) - 1;
    };
    std::vector<Vec3i> faces;
    for (const Vec3i& f : m.faces) {
      const int a = mid(f[0], f[1]), b = mid(f[1], f[2]), c = mid(f[2], f[0]);
      faces.insert(faces.end(), {Vec3i(f[0], a, c), Vec3i(a, f[1], b), Vec3i(c, b, f[2]), Vec3i(a, b, c)});
    }
    m.faces = std::move(faces);
  }
  return m;
}

// Views larger than the visibility raster (2048 px in the pipeline) are reduced for the vertex
// colouring that faint texels fade toward; the background's colour must not bleed into the object's
// rim there. A gray box on black whose sides end inside a 2x2 block of pixels (a reduced pixel at the
// rim is half box, half background), the mesh a box within a pixel of the reduced views inside it, so
// its rim vertices read that pixel: its top and bottom, which no view sees, take their colour from the
// rim's vertices, and every texel must be the views' gray (before, they came out darker).
TEST(TextureBake, BackgroundDoesNotBleedIntoTheRimOfViewsLargerThanTheRaster) {
  const Vec3f lo(-0.3995f, -0.4995f, -0.2995f), hi(0.3995f, 0.4995f, 0.2995f), inset(0.0015f, 0.0015f, 0.0015f);
  const ViewSet large = testing::boxes_views({{lo, hi}}, 2048);
  Mesh mesh = subdivided_box(lo + inset, hi - inset, 4);
  TextureBakeOptions options;
  options.atlas.texture_size = 256;
  const TextureBakeReport report = bake_texture(mesh, large, {}, options);
  ASSERT_LT(report.texels_confident, report.texels_covered);  // some texels fade toward the vertex colours
  const Image& texture = mesh.materials[0].texture;
  float worst = 0.f;
  for (float value : texture.data) worst = std::max(worst, std::abs(value - 0.5f));
  EXPECT_LT(worst, 1e-5f);
}

TEST(TextureBake, RejectsBadOptions) {
  Mesh mesh = make_icosphere(3, kRadius);
  TextureBakeOptions options;
  options.depth_tolerance_px = -1.f;
  EXPECT_THROW(bake_texture(mesh, views(), {}, options), Error);
  options = {};
  options.atlas.texture_size = 4;
  EXPECT_THROW(bake_texture(mesh, views(), {}, options), Error);
  EXPECT_EQ(mesh.face_count(), make_icosphere(3, kRadius).face_count());  // left as it was
  EXPECT_FALSE(mesh.has_uvs());
}

}  // namespace
}  // namespace u3d
