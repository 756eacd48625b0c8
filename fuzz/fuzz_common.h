#pragma once
// Shared by the libFuzzer targets of fuzz/ (docs/architecture.md, "Fuzzing"): a scratch folder for the readers that only
// take a path, and the one rule every target follows: u3d::Error is the expected way for a reader to
// reject bad input and is swallowed; anything else (another exception, a crash, a sanitizer report, a
// leak, a timeout) escapes to libFuzzer and is a finding.
#include <stdlib.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "core/error.h"

namespace u3d::fuzz {

// A folder private to this process (parallel fuzzers do not share it), removed at normal exit.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "u3d_fuzz_XXXXXX").string();
    if (!mkdtemp(pattern.data())) std::abort();
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline const std::filesystem::path& scratch_dir() {
  static const ScratchDir dir;
  return dir.path();
}

// Writes bytes to scratch_dir()/name and returns the path.
inline std::filesystem::path write_scratch_file(const std::string& name, const uint8_t* data, size_t size) {
  std::filesystem::path path = scratch_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  out.close();
  if (!out) std::abort();  // the harness itself failed, not the reader
  return path;
}

// Runs one reader call; a u3d::Error is a clean rejection.
template <class F>
void expect_clean(F&& read) {
  try {
    read();
  } catch (const u3d::Error&) {
  }
}

}  // namespace u3d::fuzz
