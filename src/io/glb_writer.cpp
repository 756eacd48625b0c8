// Binary glTF 2.0 (GLB) writer. One node, one mesh, one primitive per used material, all primitives
// sharing the vertex attributes: POSITION (with min/max), NORMAL (area-weighted), COLOR_0 (float vec3,
// LINEAR as glTF requires: our sRGB colours go through the sRGB EOTF), TEXCOORD_0 (v flipped: glTF's
// (0,0) is the top-left of the image) and uint32 indices. Materials are PBR metallic-roughness with
// metallic 0 and roughness 1, baseColorFactor linear, baseColorTexture an embedded PNG (or JPEG).
#include <algorithm>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/color_space.h"
#include "core/error.h"
#include "io/image_codec.h"
#include "io/mesh_formats.h"

namespace u3d {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

constexpr int kFloat = 5126;
constexpr int kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

// Accumulates the BIN chunk and the bufferView/accessor JSON that describe it.
class GlbBuilder {
 public:
  // Adds a tightly packed float accessor ("VEC2"/"VEC3") and returns its index.
  template <int N>
  int add_float_accessor(const std::vector<Eigen::Matrix<float, N, 1>>& values, const char* type, bool with_bounds) {
    int view = add_view(values.data(), values.size() * sizeof(float) * N, kArrayBuffer);
    json accessor = {{"bufferView", view}, {"componentType", kFloat}, {"count", values.size()}, {"type", type}};
    if (with_bounds) {
      Eigen::Matrix<float, N, 1> lo = values[0], hi = values[0];
      for (const auto& v : values) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
      accessor["min"] = std::vector<float>(lo.data(), lo.data() + N);
      accessor["max"] = std::vector<float>(hi.data(), hi.data() + N);
    }
    accessors_.push_back(accessor);
    return int(accessors_.size()) - 1;
  }

  int add_index_accessor(const std::vector<uint32_t>& indices) {
    int view = add_view(indices.data(), indices.size() * sizeof(uint32_t), kElementArrayBuffer);
    accessors_.push_back({{"bufferView", view}, {"componentType", kUnsignedInt}, {"count", indices.size()}, {"type", "SCALAR"}});
    return int(accessors_.size()) - 1;
  }

  int add_image(const std::vector<unsigned char>& bytes, TextureFormat format) {
    images_.push_back({{"bufferView", add_view(bytes.data(), bytes.size(), 0)}, {"mimeType", texture_mime_type(format)}});
    return int(images_.size()) - 1;
  }

  std::string finish(json gltf) const {
    gltf["buffers"] = json::array({{{"byteLength", bin_.size()}}});
    gltf["bufferViews"] = views_;
    gltf["accessors"] = accessors_;
    if (!images_.empty()) gltf["images"] = images_;
    std::string text = gltf.dump();
    text.resize((text.size() + 3) / 4 * 4, ' ');  // JSON chunk is padded with spaces
    std::string out;
    auto u32 = [&](uint32_t v) {
      char b[4];
      std::memcpy(b, &v, 4);
      out.append(b, 4);
    };
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(uint32_t(12 + 8 + text.size() + 8 + bin_.size()));
    u32(uint32_t(text.size()));
    u32(0x4E4F534A);  // "JSON"
    out += text;
    u32(uint32_t(bin_.size()));
    u32(0x004E4942);  // "BIN\0"
    out += bin_;
    return out;
  }

 private:
  int add_view(const void* data, size_t bytes, int target) {
    bin_.resize((bin_.size() + 3) / 4 * 4, '\0');  // every view starts 4-byte aligned
    json view = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (target) view["target"] = target;
    bin_.append(static_cast<const char*>(data), bytes);
    bin_.resize((bin_.size() + 3) / 4 * 4, '\0');  // and the chunk ends aligned
    views_.push_back(view);
    return int(views_.size()) - 1;
  }

  std::string bin_;
  json views_ = json::array();
  json accessors_ = json::array();
  json images_ = json::array();
};

float clamp01(float v) { return std::clamp(v, 0.f, 1.f); }

// glTF requires unit normals: vertices without a well-defined normal (isolated or only on degenerate
// faces) get +Z instead of zero.
std::vector<Vec3f> unit_normals(const Mesh& mesh) {
  std::vector<Vec3f> normals = vertex_normals(mesh.positions, mesh.faces);
  for (auto& n : normals)
    if (n.squaredNorm() < 0.5f) n = Vec3f::UnitZ();
  return normals;
}

json material_json(const Material& material, int texture) {
  std::vector<float> factor;
  for (int c = 0; c < 3; ++c) factor.push_back(srgb_to_linear(clamp01(material.base_color[c])));
  factor.push_back(clamp01(material.base_color[3]));
  json pbr = {{"baseColorFactor", factor}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}};
  if (texture >= 0) pbr["baseColorTexture"] = {{"index", texture}};
  json out = {{"pbrMetallicRoughness", pbr}, {"doubleSided", false}};
  if (!material.name.empty()) out["name"] = material.name;
  if (material.base_color[3] < 1.f) out["alphaMode"] = "BLEND";
  return out;
}

std::string glb_bytes(const Mesh& mesh, TextureFormat texture_format) {
  GlbBuilder builder;
  json attributes = {{"POSITION", builder.add_float_accessor<3>(mesh.positions, "VEC3", true)},
                     {"NORMAL", builder.add_float_accessor<3>(unit_normals(mesh), "VEC3", false)}};
  if (mesh.has_colors()) {
    std::vector<Vec3f> linear(mesh.colors.size());
    for (size_t i = 0; i < linear.size(); ++i)
      for (int c = 0; c < 3; ++c) linear[i][c] = srgb_to_linear(clamp01(mesh.colors[i][c]));
    attributes["COLOR_0"] = builder.add_float_accessor<3>(linear, "VEC3", false);
  }
  if (mesh.has_uvs()) {
    std::vector<Vec2f> flipped(mesh.uvs.size());
    for (size_t i = 0; i < flipped.size(); ++i) flipped[i] = Vec2f(mesh.uvs[i].x(), 1.f - mesh.uvs[i].y());
    attributes["TEXCOORD_0"] = builder.add_float_accessor<2>(flipped, "VEC2", false);
  }

  // Faces grouped by material, in face order within each group.
  size_t material_count = std::max<size_t>(mesh.materials.size(), 1);
  std::vector<std::vector<uint32_t>> indices(material_count);
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) indices[mesh.material_of(f)].push_back(uint32_t(mesh.faces[f][k]));

  json gltf = {{"asset", {{"version", "2.0"}, {"generator", "unique3d"}}},
               {"scene", 0},
               {"scenes", json::array({{{"nodes", json::array({0})}}})},
               {"nodes", json::array({{{"mesh", 0}}})}};
  json primitives = json::array(), materials = json::array(), textures = json::array();
  for (size_t m = 0; m < material_count; ++m) {
    if (indices[m].empty()) continue;  // unused materials would only draw validator warnings
    int texture = -1;
    Material material = m < mesh.materials.size() ? mesh.materials[m] : Material{};
    if (!material.texture.empty() && mesh.has_uvs()) {
      int image = builder.add_image(
          encode_image(material.texture, texture_format, "texture of material '" + material.name + "'"), texture_format);
      textures.push_back({{"sampler", 0}, {"source", image}});
      texture = int(textures.size()) - 1;
    }
    materials.push_back(material_json(material, texture));
    primitives.push_back({{"attributes", attributes},
                          {"indices", builder.add_index_accessor(indices[m])},
                          {"material", materials.size() - 1},
                          {"mode", 4}});
  }
  gltf["meshes"] = json::array({{{"primitives", primitives}}});
  gltf["materials"] = materials;
  if (!textures.empty()) {
    gltf["textures"] = textures;
    gltf["samplers"] = json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 10497}, {"wrapT", 10497}}});
  }
  return builder.finish(gltf);
}

}  // namespace

void write_glb(const Mesh& mesh, const fs::path& path, TextureFormat texture_format) {
  std::string bytes = glb_bytes(mesh, texture_format);
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.close();
    require(out.good(), "cannot write " + path.string());
  });
}

}  // namespace u3d
