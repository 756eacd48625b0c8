// Wavefront OBJ reader. OBJ indexes positions and texture coordinates separately per face corner,
// while Mesh stores one UV per vertex: a position used with several UVs (a texture seam) is split into
// one vertex per distinct (position, uv) pair. The first pair keeps the position's index so meshes
// without seams keep their vertex order.
#include <array>
#include <fstream>
#include <map>
#include <unordered_map>

#include "core/error.h"
#include "io/mesh_formats.h"
#include "io/mtl_reader.h"
#include "io/text_tokens.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

struct Corner {
  int position;
  int texcoord;  // -1 = none
};

class ObjParser {
 public:
  explicit ObjParser(const fs::path& path) : path_(path) {}

  Mesh parse() {
    std::ifstream in(path_, std::ios::binary);
    require(in.good(), "cannot open mesh file " + path_.string());
    std::string line;
    for (line_no_ = 1; std::getline(in, line); ++line_no_) parse_line(line);
    require(!in.bad(), "cannot read mesh file " + path_.string());
    return build_mesh();
  }

 private:
  std::string where() const { return path_.string() + ":" + std::to_string(line_no_); }

  void parse_line(std::string_view line) {
    line = trim(line);
    if (line.empty() || line.front() == '#') return;
    auto tokens = split_whitespace(line);
    std::string_view key = tokens[0];
    if (key == "v") parse_vertex(tokens);
    else if (key == "vt") parse_texcoord(tokens);
    else if (key == "f") parse_face(tokens);
    else if (key == "mtllib") load_material_libraries(tokens);
    else if (key == "usemtl") use_material(std::string(trim(line.substr(key.size()))));
    // vn, o, g, s, l, p and unknown statements do not affect a triangle mesh with per-vertex data.
  }

  float number(std::string_view token) const {
    float value = 0.f;
    require(parse_number(token, value), where() + ": '" + std::string(token) + "' is not a number");
    return value;
  }

  void parse_vertex(const std::vector<std::string_view>& t) {
    require(t.size() >= 4, where() + ": a vertex needs x y z");
    positions_.emplace_back(number(t[1]), number(t[2]), number(t[3]));
    // "v x y z r g b" is the common vertex-colour extension; "v x y z w" carries a weight we ignore.
    if (t.size() >= 7) {
      colors_.resize(positions_.size() - 1, Vec3f::Ones());  // earlier vertices without colour stay white
      colors_.emplace_back(number(t[4]), number(t[5]), number(t[6]));
    }
  }

  void parse_texcoord(const std::vector<std::string_view>& t) {
    require(t.size() >= 2, where() + ": a texture coordinate needs u [v]");
    texcoords_.emplace_back(number(t[1]), t.size() >= 3 ? number(t[2]) : 0.f);
  }

  // OBJ indices are 1-based; negative ones count back from the last element defined so far.
  int resolve_index(std::string_view token, size_t count, const char* what) const {
    long long index = 0;
    require(parse_number(token, index) && index != 0, where() + ": bad " + what + " index '" + std::string(token) + "'");
    long long resolved = index > 0 ? index - 1 : (long long)count + index;
    require(resolved >= 0 && resolved < (long long)count,
            where() + ": " + what + " index " + std::to_string(index) + " is out of range (" + std::to_string(count) + " defined)");
    return int(resolved);
  }

  Corner parse_corner(std::string_view token) const {
    // v, v/vt, v//vn or v/vt/vn
    size_t slash = token.find('/');
    Corner corner{resolve_index(token.substr(0, slash), positions_.size(), "vertex"), -1};
    if (slash != std::string_view::npos) {
      std::string_view rest = token.substr(slash + 1);
      std::string_view vt = rest.substr(0, rest.find('/'));
      if (!vt.empty()) corner.texcoord = resolve_index(vt, texcoords_.size(), "texture coordinate");
    }
    return corner;
  }

  void parse_face(const std::vector<std::string_view>& t) {
    require(t.size() >= 4, where() + ": a face needs at least three vertices");
    std::vector<Corner> polygon;
    for (size_t i = 1; i < t.size(); ++i) polygon.push_back(parse_corner(t[i]));
    for (size_t i = 1; i + 1 < polygon.size(); ++i) {  // fan triangulation
      triangles_.push_back({polygon[0], polygon[i], polygon[i + 1]});
      triangle_material_.push_back(current_material_);
    }
  }

  void load_material_libraries(const std::vector<std::string_view>& t) {
    for (size_t i = 1; i < t.size(); ++i) {
      fs::path library = path_.parent_path() / fs::path(std::string(t[i]));
      require(fs::exists(library), where() + ": material library " + library.string() + " does not exist");
      for (auto& [name, entry] : read_mtl(library)) library_.insert_or_assign(name, std::move(entry));
    }
  }

  void use_material(const std::string& name) {
    auto known = material_index_.find(name);
    if (known != material_index_.end()) {
      current_material_ = known->second;
      return;
    }
    Material material;
    material.name = name;
    // A name missing from the libraries is drawn plain white, as most viewers do.
    auto entry = library_.find(name);
    if (entry != library_.end()) {
      material = entry->second.material;
      if (!entry->second.texture_path.empty()) {
        require(fs::exists(entry->second.texture_path),
                where() + ": texture " + entry->second.texture_path.string() + " of material '" + name + "' does not exist");
        material.texture = load_image(entry->second.texture_path);
      }
    }
    current_material_ = int(materials_.size());
    material_index_[name] = current_material_;
    materials_.push_back(std::move(material));
  }

  Mesh build_mesh() {
    Mesh mesh;
    mesh.positions = positions_;
    if (!colors_.empty()) {
      mesh.colors = colors_;
      mesh.colors.resize(positions_.size(), Vec3f::Ones());
    }
    bool has_uvs = false;
    for (const auto& tri : triangles_)
      for (const Corner& c : tri) has_uvs |= c.texcoord >= 0;

    constexpr int kUnassigned = -2;
    std::vector<int> texcoord_of_vertex(positions_.size(), kUnassigned);
    std::map<std::pair<int, int>, int> split_vertex;  // (position, texcoord) -> vertex for seams
    auto vertex_for = [&](const Corner& c) -> int {
      if (!has_uvs) return c.position;
      int& assigned = texcoord_of_vertex[c.position];
      if (assigned == kUnassigned) assigned = c.texcoord;
      if (assigned == c.texcoord) return c.position;
      auto [it, inserted] = split_vertex.try_emplace({c.position, c.texcoord}, int(mesh.positions.size()));
      if (inserted) {
        mesh.positions.push_back(positions_[c.position]);
        if (!mesh.colors.empty()) mesh.colors.push_back(mesh.colors[c.position]);
        new_vertex_texcoords_.push_back(c.texcoord);
      }
      return it->second;
    };
    mesh.faces.reserve(triangles_.size());
    for (const auto& tri : triangles_) mesh.faces.emplace_back(vertex_for(tri[0]), vertex_for(tri[1]), vertex_for(tri[2]));

    if (has_uvs) {
      auto uv_of = [&](int texcoord) { return texcoord >= 0 ? texcoords_[texcoord] : Vec2f(0.f, 0.f); };
      mesh.uvs.reserve(mesh.positions.size());
      for (int texcoord : texcoord_of_vertex) mesh.uvs.push_back(uv_of(texcoord));
      for (int texcoord : new_vertex_texcoords_) mesh.uvs.push_back(uv_of(texcoord));
    }

    if (!materials_.empty()) {
      mesh.materials = materials_;
      int fallback = -1;  // faces before the first usemtl
      mesh.face_material.reserve(triangle_material_.size());
      for (int m : triangle_material_) {
        if (m < 0) {
          if (fallback < 0) {
            fallback = int(mesh.materials.size());
            mesh.materials.push_back(Material{"default", Vec4f::Ones(), Image()});
          }
          m = fallback;
        }
        mesh.face_material.push_back(m);
      }
    }
    return mesh;
  }

  fs::path path_;
  int line_no_ = 0;
  std::vector<Vec3f> positions_;
  std::vector<Vec3f> colors_;
  std::vector<Vec2f> texcoords_;
  std::vector<std::array<Corner, 3>> triangles_;
  std::vector<int> triangle_material_;
  std::vector<int> new_vertex_texcoords_;
  std::map<std::string, MtlEntry> library_;
  std::unordered_map<std::string, int> material_index_;
  std::vector<Material> materials_;
  int current_material_ = -1;
};

}  // namespace

Mesh read_obj(const fs::path& path) { return ObjParser(path).parse(); }

}  // namespace u3d
