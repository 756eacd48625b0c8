#pragma once
// Shared by the libFuzzer targets of fuzz/ (docs/architecture.md, "Fuzzing"): a scratch folder for the readers that only
// take a path, and the one rule every target follows: u3d::Error is the expected way for a reader to
// reject bad input and is swallowed; anything else (another exception, a crash, a sanitizer report, a
// leak, a timeout) escapes to libFuzzer and is a finding.
#include <stdlib.h>

#include <algorithm>
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

// The image decoders accept up to 2^30 pixels (core/image_decode.h), which a 30-byte header can claim;
// the fuzz run's RSS limit would report the allocation as a crash, and decoding a few million pixels
// of a mutated file takes seconds under ASan. True when the bytes claim more than 2^18 pixels (512 x
// 512) anywhere a decoder could find a size: after any PNG "IHDR" chunk type, or in any JPEG
// start-of-frame marker, wherever they stand (inside a GLB's buffer too; not inside base64 data URIs).
// Such inputs are skipped.
inline bool claims_a_huge_image(const uint8_t* data, size_t size) {
  constexpr uint64_t kMaxPixels = uint64_t(1) << 18;
  auto be16 = [&](size_t at) { return uint64_t(data[at]) << 8 | data[at + 1]; };
  auto be32 = [&](size_t at) { return be16(at) << 16 | be16(at + 2); };
  for (size_t i = 0; i + 12 <= size; ++i) {
    if (std::equal(data + i, data + i + 4, "IHDR") && be32(i + 4) * be32(i + 8) > kMaxPixels) return true;
    const uint8_t m = data[i + 1];  // SOFn: FF Cn, length, precision, height, width
    if (data[i] == 0xff && m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc &&
        be16(i + 5) * be16(i + 7) > kMaxPixels)
      return true;
  }
  return false;
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
