#pragma once
// Zip files through libzip: reading a zip a client uploaded (every regular file's name and bytes, within
// limits, refusing what no honest view folder holds) and writing a zip of result files (the OBJ with its
// material and texture).
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace u3d::server {

struct ZipEntry {
  std::string name;  // as stored in the zip: only to be matched against known names, never a path
  std::string data;
};

struct ZipLimits {
  size_t max_entries = 64;
  size_t max_total_bytes = 256u << 20;  // all files, uncompressed
};

// The regular files of the zip in `bytes` (folders skipped). An Error when the bytes are not a zip, an
// entry is a symbolic link, a name is absolute or has a ".." part, there are more than max_entries
// entries, the files hold more than max_total_bytes (counted while inflating, so a size the zip's
// directory understates is caught too), or an entry is damaged.
std::vector<ZipEntry> read_zip(const std::string& bytes, const ZipLimits& limits = {});

// Writes a zip holding each file under its name (deflated), atomically.
void write_zip(const std::filesystem::path& path,
               const std::vector<std::pair<std::string, std::filesystem::path>>& files);

}  // namespace u3d::server
