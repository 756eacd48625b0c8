// glTF 2.0 reader (.glb and .gltf, via tinygltf): every triangle primitive of every node of the default
// scene, with the node transforms applied, merged into one Mesh. COLOR_0 is linear in glTF and becomes
// sRGB here; TEXCOORD_0 is flipped to the bottom-left origin; baseColorFactor/baseColorTexture become
// materials.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cstring>
#include <map>

#include "core/color_space.h"
#include "core/error.h"
#include "io/image_codec.h"
#include "io/mesh_formats.h"
#include "io/text_tokens.h"
#include "io/tinygltf.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

// What the image callback needs: the model tinygltf is filling in, and the images decoded so far by glTF
// image index.
struct ImageLoading {
  const tinygltf::Model* model;
  std::map<int, Image> images;
};

// Image decoding callback for tinygltf. tinygltf hands over an image stored in a buffer view without
// checking that the view lies inside its buffer, so that is checked here before a byte is read.
bool decode_gltf_image(tinygltf::Image* image, const int index, std::string* err, std::string*, int, int,
                       const unsigned char* bytes, int size, void* user_data) {
  auto& loading = *static_cast<ImageLoading*>(user_data);
  const std::string what = "image " + std::to_string(index) + " '" + image->name + "'";
  try {
    if (image->bufferView >= 0) {
      const auto& views = loading.model->bufferViews;
      require(size_t(image->bufferView) < views.size(), what + " refers to a missing buffer view");
      const tinygltf::BufferView& view = views[size_t(image->bufferView)];
      require(view.buffer >= 0 && size_t(view.buffer) < loading.model->buffers.size(), what + " refers to a missing buffer");
      const size_t buffer_size = loading.model->buffers[size_t(view.buffer)].data.size();
      require(view.byteOffset <= buffer_size && view.byteLength <= buffer_size - view.byteOffset && size >= 0,
              what + ": its buffer view reaches past the end of its buffer (truncated file?)");
    }
    loading.images[index] = decode_image(bytes, size_t(size), what);
  } catch (const Error& e) {
    if (err) *err += e.what();
    return false;
  }
  return true;
}

class GltfMeshBuilder {
 public:
  GltfMeshBuilder(const tinygltf::Model& model, std::map<int, Image> images, std::string file)
      : model_(model), images_(std::move(images)), file_(std::move(file)) {}

  Mesh build() {
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      require(scene < int(model_.scenes.size()), file_ + ": default scene " + std::to_string(scene) + " does not exist");
      roots = model_.scenes[scene].nodes;
    } else {  // no scene: every node that is nobody's child
      std::vector<bool> is_child(model_.nodes.size(), false);
      for (const auto& node : model_.nodes)
        for (int child : node.children)
          if (child >= 0 && child < int(is_child.size())) is_child[child] = true;
      for (size_t n = 0; n < model_.nodes.size(); ++n)
        if (!is_child[n]) roots.push_back(int(n));
    }
    on_path_.assign(model_.nodes.size(), false);
    for (int root : roots) add_node(root, Eigen::Matrix4d::Identity());

    if (!any_color_) mesh_.colors.clear();
    if (!any_uv_) mesh_.uvs.clear();
    // One untextured white material says nothing that "no materials" does not (glTF writers, ours
    // included, must name a material even for vertex-coloured meshes).
    if (mesh_.materials.size() == 1 && mesh_.materials[0].texture.empty() && mesh_.materials[0].base_color == Vec4f::Ones())
      mesh_.materials.clear();
    if (mesh_.materials.empty()) mesh_.face_material.clear();
    return std::move(mesh_);
  }

 private:
  static Eigen::Matrix4d local_transform(const tinygltf::Node& node) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    if (node.matrix.size() == 16) {
      for (int i = 0; i < 16; ++i) m(i % 4, i / 4) = node.matrix[i];  // column-major
      return m;
    }
    if (node.scale.size() == 3) m = Eigen::Vector4d(node.scale[0], node.scale[1], node.scale[2], 1).asDiagonal();
    if (node.rotation.size() == 4) {
      Eigen::Quaterniond q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);  // glTF: x y z w
      Eigen::Matrix4d r = Eigen::Matrix4d::Identity();
      r.topLeftCorner<3, 3>() = q.normalized().toRotationMatrix();
      m = r * m;
    }
    if (node.translation.size() == 3)
      m.topRightCorner<3, 1>() += Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]);
    return m;
  }

  void add_node(int index, const Eigen::Matrix4d& parent) {
    require(index >= 0 && index < int(model_.nodes.size()), file_ + ": node " + std::to_string(index) + " does not exist");
    require(!on_path_[index], file_ + ": node " + std::to_string(index) + " is its own ancestor");
    on_path_[index] = true;
    const tinygltf::Node& node = model_.nodes[index];
    Eigen::Matrix4d world = parent * local_transform(node);
    if (node.mesh >= 0) {
      require(node.mesh < int(model_.meshes.size()), file_ + ": mesh " + std::to_string(node.mesh) + " does not exist");
      SharedVertices shared;
      for (const auto& primitive : model_.meshes[node.mesh].primitives) add_primitive(primitive, world, shared);
    }
    for (int child : node.children) add_node(child, world);
    on_path_[index] = false;
  }

  // Accessor values as doubles, `components` per element, normalized integers mapped to [0,1]/[-1,1].
  std::vector<double> read_accessor(int index, int components, const char* what) const {
    std::string name = file_ + ": " + what + " accessor " + std::to_string(index);
    require(index >= 0 && index < int(model_.accessors.size()), name + " does not exist");
    const tinygltf::Accessor& accessor = model_.accessors[index];
    require(!accessor.sparse.isSparse, name + " is sparse, which is not supported");
    int n = tinygltf::GetNumComponentsInType(uint32_t(accessor.type));
    require(n == components || (components == 3 && n == 4 && std::string(what) == "COLOR_0"),
            name + " has " + std::to_string(n) + " components, expected " + std::to_string(components));
    int component_size = tinygltf::GetComponentSizeInBytes(uint32_t(accessor.componentType));
    require(component_size > 0, name + " has an unknown component type");
    require(accessor.count < (size_t(1) << 31), name + " has an implausible count " + std::to_string(accessor.count));
    if (accessor.bufferView < 0) return std::vector<double>(accessor.count * size_t(components), 0.0);  // zeros, per the spec

    require(accessor.bufferView < int(model_.bufferViews.size()), name + " refers to a missing buffer view");
    const tinygltf::BufferView& view = model_.bufferViews[accessor.bufferView];
    require(view.buffer >= 0 && view.buffer < int(model_.buffers.size()), name + " refers to a missing buffer");
    const std::vector<unsigned char>& buffer = model_.buffers[view.buffer].data;
    size_t element_size = size_t(component_size) * n;
    size_t stride = view.byteStride ? view.byteStride : element_size;
    size_t start = view.byteOffset + accessor.byteOffset;
    if (accessor.count > 0) {
      size_t end = start + stride * (accessor.count - 1) + element_size;
      require(end <= view.byteOffset + view.byteLength && view.byteOffset + view.byteLength <= buffer.size(),
              name + " reaches past the end of its buffer (truncated file?)");
    }
    std::vector<double> out(accessor.count * size_t(components));
    for (size_t i = 0; i < accessor.count; ++i)
      for (int c = 0; c < components; ++c) {
        const unsigned char* p = buffer.data() + start + i * stride + size_t(c) * component_size;
        out[i * components + c] = component_value(p, accessor.componentType, accessor.normalized);
      }
    return out;
  }

  static double component_value(const unsigned char* p, int type, bool normalized) {
    auto load = [p](auto value) {
      std::memcpy(&value, p, sizeof(value));
      return value;
    };
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        double v = load(int8_t());
        return normalized ? std::max(v / 127.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
        double v = load(uint8_t());
        return normalized ? v / 255.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        double v = load(int16_t());
        return normalized ? std::max(v / 32767.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        double v = load(uint16_t());
        return normalized ? v / 65535.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return load(uint32_t());
      case TINYGLTF_COMPONENT_TYPE_FLOAT: return load(float());
      default: return 0.0;
    }
  }

  // Triangle corner indices (into this primitive's vertices) for triangles, strips and fans.
  std::vector<int> triangle_corners(const tinygltf::Primitive& primitive, size_t vertex_count) const {
    std::vector<int> order;
    if (primitive.indices >= 0) {
      for (double v : read_accessor(primitive.indices, 1, "index")) {
        require(v >= 0 && v < double(vertex_count), file_ + ": index " + std::to_string(v) + " is out of range (" +
                                                         std::to_string(vertex_count) + " vertices)");
        order.push_back(int(v));
      }
    } else {
      for (size_t i = 0; i < vertex_count; ++i) order.push_back(int(i));
    }
    std::vector<int> corners;
    if (primitive.mode == TINYGLTF_MODE_TRIANGLES) {
      corners.assign(order.begin(), order.begin() + order.size() / 3 * 3);
    } else if (primitive.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      for (size_t i = 0; i + 2 < order.size(); ++i) {
        bool odd = i % 2;  // every other strip triangle is reversed to keep one winding
        corners.insert(corners.end(), {order[i + (odd ? 1 : 0)], order[i + (odd ? 0 : 1)], order[i + 2]});
      }
    } else if (primitive.mode == TINYGLTF_MODE_TRIANGLE_FAN) {
      for (size_t i = 1; i + 1 < order.size(); ++i) corners.insert(corners.end(), {order[0], order[i], order[i + 1]});
    }
    return corners;
  }

  int material_index(int gltf_material) {
    auto known = material_map_.find(gltf_material);
    if (known != material_map_.end()) return known->second;
    Material material;
    if (gltf_material >= 0) {
      require(gltf_material < int(model_.materials.size()), file_ + ": material " + std::to_string(gltf_material) + " does not exist");
      const tinygltf::Material& source = model_.materials[gltf_material];
      material.name = source.name;
      const auto& pbr = source.pbrMetallicRoughness;
      for (int c = 0; c < 4 && c < int(pbr.baseColorFactor.size()); ++c) {
        float v = float(std::clamp(pbr.baseColorFactor[c], 0.0, 1.0));
        material.base_color[c] = c < 3 ? linear_to_srgb(v) : v;
      }
      if (pbr.baseColorTexture.index >= 0) {
        int texture = pbr.baseColorTexture.index;
        require(texture < int(model_.textures.size()), file_ + ": texture " + std::to_string(texture) + " does not exist");
        auto image = images_.find(model_.textures[texture].source);
        require(image != images_.end(), file_ + ": the image of texture " + std::to_string(texture) +
                                            " could not be loaded (missing file or unsupported format)");
        material.texture = image->second;
      }
    } else {
      material.name = "default";
    }
    int index = int(mesh_.materials.size());
    mesh_.materials.push_back(std::move(material));
    material_map_[gltf_material] = index;
    return index;
  }

  // Primitives of one mesh instance that use the same attribute accessors (one vertex buffer, several
  // index lists, as our writer does per material) share their vertices instead of duplicating them.
  using SharedVertices = std::map<std::array<int, 3>, size_t>;

  void add_primitive(const tinygltf::Primitive& primitive, const Eigen::Matrix4d& world, SharedVertices& shared) {
    if (primitive.mode != TINYGLTF_MODE_TRIANGLES && primitive.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        primitive.mode != TINYGLTF_MODE_TRIANGLE_FAN)
      return;  // points and lines have no surface
    auto attribute = [&](const char* name) {
      auto it = primitive.attributes.find(name);
      return it == primitive.attributes.end() ? -1 : it->second;
    };
    int position_accessor = attribute("POSITION");
    require(position_accessor >= 0 && position_accessor < int(model_.accessors.size()),
            file_ + ": a triangle primitive has no valid POSITION attribute");
    int color_accessor = attribute("COLOR_0");
    int uv_accessor = attribute("TEXCOORD_0");
    size_t count = model_.accessors[position_accessor].count;
    auto [existing, is_new] = shared.try_emplace({position_accessor, color_accessor, uv_accessor}, mesh_.positions.size());
    size_t base = existing->second;
    if (is_new) add_vertices(position_accessor, color_accessor, uv_accessor, world);

    // A mirroring transform turns counter-clockwise triangles clockwise: swap two corners back.
    bool mirrored = world.topLeftCorner<3, 3>().determinant() < 0;
    int material = material_index(primitive.material);
    std::vector<int> corners = triangle_corners(primitive, count);
    for (size_t i = 0; i + 2 < corners.size(); i += 3) {
      Vec3i face(int(base) + corners[i], int(base) + corners[i + 1], int(base) + corners[i + 2]);
      if (mirrored) std::swap(face[1], face[2]);
      mesh_.faces.push_back(face);
      mesh_.face_material.push_back(material);
    }
  }

  void add_vertices(int position_accessor, int color_accessor, int uv_accessor, const Eigen::Matrix4d& world) {
    std::vector<double> positions = read_accessor(position_accessor, 3, "POSITION");
    size_t count = positions.size() / 3;
    for (size_t i = 0; i < count; ++i) {
      Eigen::Vector4d p = world * Eigen::Vector4d(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2], 1.0);
      mesh_.positions.emplace_back(float(p.x()), float(p.y()), float(p.z()));
    }

    if (color_accessor >= 0) {
      any_color_ = true;
      std::vector<double> colors = read_accessor(color_accessor, 3, "COLOR_0");
      require(colors.size() == 3 * count, file_ + ": COLOR_0 and POSITION counts differ");
      for (size_t i = 0; i < count; ++i) {
        Vec3f c;
        for (int k = 0; k < 3; ++k) c[k] = linear_to_srgb(float(std::clamp(colors[3 * i + k], 0.0, 1.0)));
        mesh_.colors.push_back(c);
      }
    } else {
      mesh_.colors.resize(mesh_.positions.size(), Vec3f::Ones());
    }

    if (uv_accessor >= 0) {
      any_uv_ = true;
      std::vector<double> uvs = read_accessor(uv_accessor, 2, "TEXCOORD_0");
      require(uvs.size() == 2 * count, file_ + ": TEXCOORD_0 and POSITION counts differ");
      for (size_t i = 0; i < count; ++i) mesh_.uvs.emplace_back(float(uvs[2 * i]), float(1.0 - uvs[2 * i + 1]));
    } else {
      mesh_.uvs.resize(mesh_.positions.size(), Vec2f::Zero());
    }
  }

  const tinygltf::Model& model_;
  std::map<int, Image> images_;
  std::string file_;
  Mesh mesh_;
  bool any_color_ = false;
  bool any_uv_ = false;
  std::vector<bool> on_path_;
  std::map<int, int> material_map_;
};

// Required extensions we honour: quantized attributes are read by the generic accessor code, and the
// material ones only change shading. Anything else required (Draco, meshopt, ...) cannot be read.
bool extension_supported(const std::string& name) {
  return name == "KHR_mesh_quantization" || name == "KHR_materials_unlit" || name == "KHR_materials_emissive_strength";
}

// tinygltf's file reader for the glTF and the files its URIs name (buffers, images), refusing anything
// that is not a regular file: a folder, or a device or pipe, which would block (/dev/stdin) or read
// until memory runs out (/dev/zero).
bool read_regular_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    if (err) *err += path + " is a folder or device, not a file\n";
    return false;
  }
  return tinygltf::ReadWholeFile(out, err, path, user);
}

}  // namespace

Mesh read_gltf(const fs::path& path) {
  const std::string file = path.string();
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  ImageLoading images{&model, {}};
  loader.SetImageLoader(&decode_gltf_image, &images);
  loader.SetFsCallbacks({&tinygltf::FileExists, &tinygltf::ExpandFilePath, &read_regular_file, &tinygltf::WriteWholeFile,
                         nullptr});
  std::string err, warn;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  bool ok = false;
  try {
    ok = ext == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, file)
                       : loader.LoadASCIIFromFile(&model, &err, &warn, file);
  } catch (const std::exception& e) {  // tinygltf's parser lets some index errors escape as exceptions
    throw Error("cannot read glTF file " + file + ": " + e.what());
  }
  require(ok, "cannot read glTF file " + file + ": " + std::string(trim(err.empty() ? warn : err)));
  for (const auto& extension : model.extensionsRequired)
    require(extension_supported(extension), file + ": requires glTF extension " + extension + ", which is not supported");
  return GltfMeshBuilder(model, std::move(images.images), file).build();
}

}  // namespace u3d
