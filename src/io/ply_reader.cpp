// Stanford PLY reader: ascii, binary_little_endian and binary_big_endian; vertex positions, colours
// (red/green/blue as uchar, ushort or float), UVs (s/t, u/v, texture_u/texture_v) and polygon faces
// (vertex_indices lists, fan-triangulated). Elements other than vertex and face are skipped.
// A "comment TextureFile <file>" header line (MeshLab's convention) loads a texture for the UVs.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/error.h"
#include "io/mesh_formats.h"
#include "io/text_tokens.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  std::string texture_file;
  size_t body_offset = 0;
};

bool parse_type(std::string_view name, PlyType& type) {
  static const std::pair<std::string_view, PlyType> kTypes[] = {
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& [n, t] : kTypes)
    if (n == name) {
      type = t;
      return true;
    }
  return false;
}

size_t type_size(PlyType type) {
  switch (type) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 0;
}

// Integer colour channels span the whole type range; float ones are already in [0, 1].
float color_scale(PlyType type) {
  switch (type) {
    case PlyType::Int8: return 1.f / 127.f;
    case PlyType::UInt8: return 1.f / 255.f;
    case PlyType::Int16: return 1.f / 32767.f;
    case PlyType::UInt16: return 1.f / 65535.f;
    case PlyType::Int32: return 1.f / 2147483647.f;
    case PlyType::UInt32: return 1.f / 4294967295.f;
    default: return 1.f;
  }
}

PlyHeader parse_header(const std::string& data, const std::string& file) {
  PlyHeader header;
  std::istringstream in(data);
  std::string line;
  require(std::getline(in, line) && trim(line) == "ply", file + ": not a PLY file (missing 'ply' magic)");
  bool has_format = false;
  for (int line_no = 2; std::getline(in, line); ++line_no) {
    if (in.eof()) break;  // the last header line always ends with a newline: this one was cut off
    std::string where = file + ": header line " + std::to_string(line_no);
    auto tokens = split_whitespace(line);
    if (tokens.empty()) continue;
    std::string_view key = tokens[0];
    if (key == "end_header") {
      require(has_format, file + ": PLY header has no format line");
      header.body_offset = size_t(in.tellg());
      return header;
    }
    if (key == "format") {
      require(tokens.size() >= 2, where + ": format without a value");
      if (tokens[1] == "ascii") header.format = PlyFormat::Ascii;
      else if (tokens[1] == "binary_little_endian") header.format = PlyFormat::BinaryLittleEndian;
      else if (tokens[1] == "binary_big_endian") header.format = PlyFormat::BinaryBigEndian;
      else throw Error(where + ": unknown PLY format '" + std::string(tokens[1]) + "'");
      has_format = true;
    } else if (key == "comment" || key == "obj_info") {
      if (tokens.size() >= 3 && tokens[1] == "TextureFile")
        header.texture_file = std::string(trim(std::string_view(line).substr(size_t(tokens[2].data() - line.data()))));
    } else if (key == "element") {
      PlyElement element;
      require(tokens.size() == 3 && parse_number(tokens[2], element.count), where + ": expected 'element <name> <count>'");
      element.name = std::string(tokens[1]);
      header.elements.push_back(element);
    } else if (key == "property") {
      require(!header.elements.empty(), where + ": property before any element");
      PlyProperty property;
      bool ok = false;
      if (tokens.size() == 5 && tokens[1] == "list") {
        property.is_list = true;
        ok = parse_type(tokens[2], property.count_type) && parse_type(tokens[3], property.type);
        property.name = std::string(tokens[4]);
      } else if (tokens.size() == 3) {
        ok = parse_type(tokens[1], property.type);
        property.name = std::string(tokens[2]);
      }
      require(ok, where + ": cannot parse property '" + std::string(trim(line)) + "'");
      header.elements.back().properties.push_back(property);
    } else {
      throw Error(where + ": unexpected header line '" + std::string(trim(line)) + "'");
    }
  }
  throw Error(file + ": PLY header has no end_header (truncated or not a PLY file)");
}

// Reads the body value by value, in either encoding.
class PlyBodyReader {
 public:
  PlyBodyReader(const std::string& data, size_t offset, PlyFormat format, std::string file)
      : data_(data), pos_(offset), format_(format), file_(std::move(file)) {}

  double next(PlyType type) { return format_ == PlyFormat::Ascii ? next_text() : next_binary(type); }
  // Bytes not read yet: every value takes at least one.
  size_t remaining() const { return data_.size() - pos_; }

 private:
  double next_text() {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    size_t start = pos_;
    while (pos_ < data_.size() && !std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    require(pos_ > start, file_ + ": unexpected end of data (truncated file?)");
    double value = 0;
    std::string_view token(data_.data() + start, pos_ - start);
    require(parse_number(token, value), file_ + ": '" + std::string(token.substr(0, 40)) + "' is not a number");
    return value;
  }

  double next_binary(PlyType type) {
    size_t size = type_size(type);
    require(pos_ + size <= data_.size(), file_ + ": unexpected end of data (truncated file?)");
    unsigned char bytes[8];
    std::memcpy(bytes, data_.data() + pos_, size);
    pos_ += size;
    bool swap = (format_ == PlyFormat::BinaryBigEndian) != (std::endian::native == std::endian::big);
    if (swap) std::reverse(bytes, bytes + size);
    switch (type) {
      case PlyType::Int8: return as<int8_t>(bytes);
      case PlyType::UInt8: return as<uint8_t>(bytes);
      case PlyType::Int16: return as<int16_t>(bytes);
      case PlyType::UInt16: return as<uint16_t>(bytes);
      case PlyType::Int32: return as<int32_t>(bytes);
      case PlyType::UInt32: return as<uint32_t>(bytes);
      case PlyType::Float32: return as<float>(bytes);
      case PlyType::Float64: return as<double>(bytes);
    }
    return 0;
  }

  template <typename T>
  static double as(const unsigned char* bytes) {
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return double(value);
  }

  const std::string& data_;
  size_t pos_;
  PlyFormat format_;
  std::string file_;
};

// Which vertex slot a property fills: 0-2 position, 3-5 colour, 6-7 UV, -1 ignored.
int vertex_slot(const std::string& name) {
  static const std::pair<const char*, int> kSlots[] = {
      {"x", 0}, {"y", 1}, {"z", 2},
      {"red", 3}, {"green", 4}, {"blue", 5}, {"r", 3}, {"g", 4}, {"b", 5},
      {"diffuse_red", 3}, {"diffuse_green", 4}, {"diffuse_blue", 5},
      {"s", 6}, {"t", 7}, {"u", 6}, {"v", 7}, {"texture_u", 6}, {"texture_v", 7},
      {"texture_s", 6}, {"texture_t", 7}};
  for (const auto& [n, slot] : kSlots)
    if (name == n) return slot;
  return -1;
}

// Casting an out-of-range double to an integer is undefined: check before every conversion.
int to_index(double value, const std::string& file, const char* what) {
  if (!(value >= 0 && value < 2147483647.0)) {
    std::ostringstream text;  // shortest form: integers print without decimals
    text << std::setprecision(17) << value;
    throw Error(file + ": " + what + " " + text.str() + " is out of range");
  }
  return int(value);
}

void skip_property(PlyBodyReader& body, const PlyProperty& property, const std::string& file) {
  int n = property.is_list ? to_index(body.next(property.count_type), file, "list length") : 1;
  for (int i = 0; i < n; ++i) body.next(property.type);
}

void read_vertices(PlyBodyReader& body, const PlyElement& element, Mesh& mesh, const std::string& file) {
  std::vector<int> slots;
  bool present[8] = {};
  for (const auto& p : element.properties) {
    int slot = p.is_list ? -1 : vertex_slot(p.name);
    slots.push_back(slot);
    if (slot >= 0) present[slot] = true;
  }
  require(present[0] && present[1] && present[2], file + ": vertex element lacks x, y or z");
  bool has_colors = present[3] && present[4] && present[5];
  bool has_uvs = present[6] && present[7];
  mesh.positions.resize(element.count);
  if (has_colors) mesh.colors.resize(element.count);
  if (has_uvs) mesh.uvs.resize(element.count);
  for (size_t v = 0; v < element.count; ++v) {
    for (size_t k = 0; k < slots.size(); ++k) {
      const PlyProperty& p = element.properties[k];
      int slot = slots[k];
      if (slot < 0) {
        skip_property(body, p, file);
        continue;
      }
      double value = body.next(p.type);
      if (slot < 3) mesh.positions[v][slot] = float(value);
      else if (slot < 6) {
        if (has_colors) mesh.colors[v][slot - 3] = float(value) * color_scale(p.type);
      } else if (has_uvs) {
        mesh.uvs[v][slot - 6] = float(value);
      }
    }
  }
}

void read_faces(PlyBodyReader& body, const PlyElement& element, Mesh& mesh, const std::string& file) {
  int index_property = -1;
  for (size_t k = 0; k < element.properties.size(); ++k) {
    const auto& p = element.properties[k];
    if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) index_property = int(k);
  }
  require(index_property >= 0, file + ": face element has no vertex_indices list");
  std::vector<int> polygon;
  for (size_t f = 0; f < element.count; ++f) {
    for (size_t k = 0; k < element.properties.size(); ++k) {
      const PlyProperty& p = element.properties[k];
      if (int(k) != index_property) {
        skip_property(body, p, file);
        continue;
      }
      int count = to_index(body.next(p.count_type), file, "face vertex count");
      require(count >= 3, file + ": face " + std::to_string(f) + " has " + std::to_string(count) + " vertices (need 3 or more)");
      // A corrupt count must not allocate gigabytes before the data runs out.
      require(size_t(count) <= body.remaining(), file + ": face " + std::to_string(f) + " claims " + std::to_string(count) +
                                                     " vertices but the file is too short (truncated?)");
      polygon.resize(size_t(count));
      for (int& index : polygon) index = to_index(body.next(p.type), file, "vertex index");
      for (size_t i = 1; i + 1 < polygon.size(); ++i) mesh.faces.emplace_back(polygon[0], polygon[i], polygon[i + 1]);
    }
  }
}

}  // namespace

Mesh read_ply(const fs::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  require(in.good(), "cannot open mesh file " + file);
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  require(!in.bad(), "cannot read mesh file " + file);

  PlyHeader header = parse_header(data, file);
  // A corrupt element count must not trigger a giant allocation: every item needs at least one byte
  // per property (binary: its scalar size; ascii: one character).
  size_t body_size = data.size() - header.body_offset;
  for (const PlyElement& element : header.elements) {
    size_t item_bytes = 0;
    for (const auto& p : element.properties)
      item_bytes += header.format == PlyFormat::Ascii ? 1 : type_size(p.is_list ? p.count_type : p.type);
    require(element.count <= body_size / std::max<size_t>(item_bytes, 1),
            file + ": element '" + element.name + "' claims " + std::to_string(element.count) + " items but the file is too short (truncated?)");
  }
  PlyBodyReader body(data, header.body_offset, header.format, file);
  Mesh mesh;
  bool seen_vertices = false;
  for (const PlyElement& element : header.elements) {
    if (element.name == "vertex") {
      read_vertices(body, element, mesh, file);
      seen_vertices = true;
    } else if (element.name == "face") {
      require(seen_vertices, file + ": face element before the vertex element");
      read_faces(body, element, mesh, file);
    } else {
      for (size_t i = 0; i < element.count; ++i)
        for (const auto& p : element.properties) skip_property(body, p, file);
    }
  }
  if (!header.texture_file.empty() && mesh.has_uvs()) {
    fs::path texture = path.parent_path() / header.texture_file;
    require(fs::exists(texture), file + ": texture " + texture.string() + " does not exist");
    mesh.materials.push_back(Material{"texture", Vec4f::Ones(), load_image(texture)});
  }
  return mesh;
}

}  // namespace u3d
