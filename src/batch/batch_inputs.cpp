#include "batch/batch_inputs.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <map>

#include "batch/shard.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/view_set.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

bool is_photo_file(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

bool hidden(const fs::path& path) { return path.filename().string().front() == '.'; }

// The first view image missing from `dir`, or empty when it holds the whole view set.
std::string missing_view_file(const fs::path& dir) {
  for (View v : kAllViews)
    for (bool normal : {false, true})
      if (!fs::is_regular_file(dir / view_file_name(v, normal))) return view_file_name(v, normal);
  return {};
}

std::string sanitized(const std::string& text) {
  std::string name = text;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  if (name.empty() || name.front() == '.') name.insert(name.begin(), '_');
  return name;
}

std::string hex8(uint64_t hash) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return std::string(text, 8);
}

}  // namespace

const char* batch_mode_name(BatchMode mode) { return mode == BatchMode::Generate ? "generate" : "reconstruct"; }

std::vector<BatchInput> name_batch_inputs(const std::vector<fs::path>& paths, const std::vector<std::string>& listed,
                                          const std::vector<BatchMode>& modes) {
  std::vector<BatchInput> inputs;
  std::map<std::string, int> uses;
  for (size_t i = 0; i < paths.size(); ++i) {
    const fs::path& p = paths[i];
    const std::string base = modes[i] == BatchMode::Generate ? p.stem().string() : p.filename().string();
    inputs.push_back({p, sanitized(base), modes[i]});
    ++uses[inputs.back().name];
  }
  for (size_t i = 0; i < inputs.size(); ++i)
    if (uses[inputs[i].name] > 1) inputs[i].name.append(1, '-').append(hex8(stable_hash(listed[i])));
  std::sort(inputs.begin(), inputs.end(), [](const BatchInput& a, const BatchInput& b) { return a.name < b.name; });
  for (size_t i = 1; i < inputs.size(); ++i)
    require(inputs[i].name != inputs[i - 1].name,
            "inputs " + inputs[i - 1].path.string() + " and " + inputs[i].path.string() + " would both write " +
                inputs[i].name + "/ (the same file listed twice?)");
  return inputs;
}

std::vector<BatchInput> list_batch_inputs(const fs::path& source) {
  require(path_exists(source), "inputs " + source.string() + " do not exist");
  std::vector<fs::path> paths;
  std::vector<std::string> listed;
  std::vector<BatchMode> modes;
  if (fs::is_directory(source)) {
    require(!missing_view_file(source).empty(),
            "inputs " + source.string() + " is a view folder itself: give the folder that holds view folders (or use "
            "`unique3d reconstruct` for one)");
    std::vector<fs::path> entries;
    for (const fs::directory_entry& e : fs::directory_iterator(source)) entries.push_back(e.path());
    std::sort(entries.begin(), entries.end());
    std::vector<std::string> skipped;
    for (const fs::path& p : entries) {
      if (hidden(p)) continue;
      if (fs::is_directory(p)) {
        const std::string missing = missing_view_file(p);
        require(missing.empty(), "inputs: folder " + p.string() + " is not a view folder: it has no " + missing);
        modes.push_back(BatchMode::Reconstruct);
      } else if (fs::is_regular_file(p) && is_photo_file(p)) {
        modes.push_back(BatchMode::Generate);
      } else {
        skipped.push_back(p.filename().string());
        continue;
      }
      paths.push_back(p);
      listed.push_back(p.filename().string());
    }
    if (!skipped.empty()) {
      std::string names;
      for (const std::string& s : skipped) names += (names.empty() ? "" : ", ") + s;
      progress("inputs: skipped " + std::to_string(skipped.size()) + " entries of " + source.string() +
               " that are neither photos (.png, .jpg) nor view folders: " + names);
    }
  } else {
    std::ifstream list(source);
    require(bool(list), "cannot read the list of inputs " + source.string());
    const fs::path base = source.parent_path();
    int number = 0;
    for (std::string line; std::getline(list, line);) {
      ++number;
      const size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      const size_t last = line.find_last_not_of(" \t\r");
      const std::string entry = line.substr(first, last - first + 1);
      const fs::path p = fs::path(entry).is_absolute() ? fs::path(entry) : base / entry;
      const std::string where = source.string() + ":" + std::to_string(number) + ": ";
      require(path_exists(p), where + p.string() + " does not exist");
      if (fs::is_directory(p)) {
        const std::string missing = missing_view_file(p);
        require(missing.empty(), where + "folder " + p.string() + " is not a view folder: it has no " + missing);
        modes.push_back(BatchMode::Reconstruct);
      } else {
        require(is_photo_file(p), where + p.string() + " is neither a photo (.png, .jpg) nor a view folder");
        modes.push_back(BatchMode::Generate);
      }
      paths.push_back(p);
      listed.push_back(entry);
    }
  }
  require(!paths.empty(), "inputs " + source.string() + " hold no photo and no view folder");
  return name_batch_inputs(paths, listed, modes);
}

}  // namespace u3d
