#include "io/mtl_reader.h"

#include <cmath>
#include <fstream>

#include "core/error.h"
#include "io/text_tokens.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

// Texture-map options that precede the file name in map_Kd, with their argument counts.
int option_argument_count(std::string_view option) {
  if (option == "-blendu" || option == "-blendv" || option == "-cc" || option == "-clamp" || option == "-bm" ||
      option == "-texres" || option == "-imfchan" || option == "-boost" || option == "-type")
    return 1;
  if (option == "-mm") return 2;
  if (option == "-o" || option == "-s" || option == "-t") return 3;
  return -1;
}

// The file name is what is left after the options; it may contain spaces.
std::string_view texture_file_name(std::string_view rest) {
  auto tokens = split_whitespace(rest);
  size_t i = 0;
  while (i < tokens.size()) {
    int args = option_argument_count(tokens[i]);
    if (args < 0) break;
    ++i;
    // -o, -s, -t and -mm take up to `args` numbers; the others exactly one word.
    for (int a = 0; a < args && i < tokens.size(); ++a) {
      double number;
      if (args > 1 && !parse_number(tokens[i], number)) break;
      ++i;
    }
  }
  if (i >= tokens.size()) return {};
  return trim(rest.substr(size_t(tokens[i].data() - rest.data())));
}

}  // namespace

std::map<std::string, MtlEntry> read_mtl(const fs::path& path) {
  std::error_code ec;
  require(fs::exists(path, ec), "material library not found: " + path.string());
  // A folder reads as empty; a device or pipe would block (/dev/stdin) or never end (/dev/zero).
  require(fs::is_regular_file(path, ec), "material library " + path.string() + " is a folder or device, not a file");
  std::ifstream in(path, std::ios::binary);
  require(in.good(), "cannot open material library " + path.string());
  std::map<std::string, MtlEntry> materials;
  MtlEntry* current = nullptr;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    std::string_view text = trim(line);
    if (text.empty() || text.front() == '#') continue;
    auto tokens = split_whitespace(text);
    std::string_view key = tokens[0];
    std::string_view rest = trim(text.substr(key.size()));
    auto where = [&] { return path.string() + ":" + std::to_string(line_no); };
    if (key == "newmtl") {
      require(!rest.empty(), where() + ": newmtl without a name");
      current = &materials[std::string(rest)];
      current->material.name = std::string(rest);
      continue;
    }
    if (key != "Kd" && key != "d" && key != "Tr" && key != "map_Kd") continue;
    require(current != nullptr, where() + ": " + std::string(key) + " before any newmtl");
    if (key == "Kd") {
      require(tokens.size() >= 4, where() + ": Kd needs three numbers");
      for (int c = 0; c < 3; ++c)
        require(parse_number(tokens[c + 1], current->material.base_color[c]) &&
                    std::isfinite(current->material.base_color[c]),
                where() + ": bad Kd value '" + std::string(tokens[c + 1]) + "'");
    } else if (key == "d" || key == "Tr") {
      float value = 1.f;
      require(tokens.size() >= 2 && parse_number(tokens.back(), value) && std::isfinite(value),
              where() + ": bad " + std::string(key) + " value");
      current->material.base_color[3] = key == "d" ? value : 1.f - value;  // Tr is transparency = 1 - d
    } else {
      std::string_view name = texture_file_name(rest);
      require(!name.empty(), where() + ": map_Kd without a file name");
      current->texture_path = path.parent_path() / fs::path(std::string(name));
    }
  }
  require(!in.bad(), "cannot read material library " + path.string());
  return materials;
}

}  // namespace u3d
