// Wavefront OBJ writer: model.obj + model.mtl (when the mesh has materials) + one PNG (or JPEG) per textured
// material. Vertex colours use the "v x y z r g b" extension; UVs are written per vertex (vt i == v i).
#include <fstream>
#include <set>

#include "core/error.h"
#include "io/companion_files.h"
#include "io/mesh_formats.h"
#include "io/number_format.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out.write(text.data(), std::streamsize(text.size()));
  out.close();
  require(out.good(), "cannot write " + path.string());
}

// Material names must be unique, non-empty single lines for usemtl/newmtl to refer to them.
std::vector<std::string> unique_material_names(const std::vector<Material>& materials) {
  std::vector<std::string> names;
  std::set<std::string> used;
  for (size_t i = 0; i < materials.size(); ++i) {
    std::string name = materials[i].name;
    for (char& c : name)
      if (c == '\n' || c == '\r' || c == '\t') c = '_';
    while (!name.empty() && name.front() == ' ') name.erase(name.begin());
    while (!name.empty() && name.back() == ' ') name.pop_back();
    if (name.empty() || used.count(name)) name = "material" + std::to_string(i);
    while (used.count(name)) name += "_";
    used.insert(name);
    names.push_back(name);
  }
  return names;
}

std::string mtl_text(const Mesh& mesh, const std::vector<std::string>& names, const std::vector<fs::path>& textures) {
  std::string text = "# written by unique3d\n";
  for (size_t i = 0; i < mesh.materials.size(); ++i) {
    const Vec4f& color = mesh.materials[i].base_color;
    text += "\nnewmtl " + names[i] + "\nKd";
    for (int c = 0; c < 3; ++c) {
      text += ' ';
      append_number(text, color[c]);
    }
    text += "\nd ";
    append_number(text, color[3]);
    text += "\nillum 1\n";
    if (!textures[i].empty()) text += "map_Kd " + textures[i].filename().string() + "\n";
  }
  return text;
}

std::string obj_text(const Mesh& mesh, const fs::path& mtl_path, const std::vector<std::string>& names) {
  std::string text = "# written by unique3d\n";
  if (!mtl_path.empty()) text += "mtllib " + mtl_path.filename().string() + "\n";
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    text += 'v';
    for (int c = 0; c < 3; ++c) {
      text += ' ';
      append_number(text, mesh.positions[i][c]);
    }
    if (mesh.has_colors())
      for (int c = 0; c < 3; ++c) {
        text += ' ';
        append_number(text, mesh.colors[i][c]);
      }
    text += '\n';
  }
  for (const Vec2f& uv : mesh.uvs) {
    text += "vt ";
    append_number(text, uv.x());
    text += ' ';
    append_number(text, uv.y());
    text += '\n';
  }
  int current_material = -1;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!names.empty() && mesh.material_of(f) != current_material) {
      current_material = mesh.material_of(f);
      text += "usemtl " + names[current_material] + "\n";
    }
    text += 'f';
    for (int k = 0; k < 3; ++k) {
      std::string index = std::to_string(mesh.faces[f][k] + 1);
      text += ' ' + index;
      if (mesh.has_uvs()) text += '/' + index;
    }
    text += '\n';
  }
  return text;
}

}  // namespace

void write_obj(const Mesh& mesh, const fs::path& path, TextureFormat texture_format) {
  std::vector<std::string> names = unique_material_names(mesh.materials);
  int textured = 0;
  for (const auto& m : mesh.materials) textured += !m.texture.empty() && mesh.has_uvs();
  std::vector<fs::path> textures(mesh.materials.size());
  for (size_t i = 0; i < mesh.materials.size(); ++i)
    if (!mesh.materials[i].texture.empty() && mesh.has_uvs()) textures[i] = texture_path_for(path, int(i), textured > 1, texture_format);
  fs::path mtl_path = mesh.materials.empty() ? fs::path() : fs::path(path).replace_extension(".mtl");

  // Companions first, the .obj last: a reader never sees an .obj whose files are missing.
  CompanionFiles files;
  for (size_t i = 0; i < textures.size(); ++i)
    if (!textures[i].empty()) files.write_image(mesh.materials[i].texture, textures[i]);
  if (!mtl_path.empty())
    files.write(mtl_path, [&](const fs::path& tmp) { write_text(tmp, mtl_text(mesh, names, textures)); });
  files.write(path, [&](const fs::path& tmp) { write_text(tmp, obj_text(mesh, mtl_path, names)); });
  files.commit();
}

}  // namespace u3d
