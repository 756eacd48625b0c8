#pragma once
// The directory of a zip archive and CRC-32 checks for its records: where each record's data lies, so a
// torch.save checkpoint can be read in place (pth_reader.h), and its CRC, so a flipped byte inside one does
// not load as a silently wrong weight.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace u3d::nn {

struct ZipRecord {
  uint32_t crc = 0;
  uint64_t size = 0;         // uncompressed bytes
  uint64_t offset = 0;       // where the data starts in the file
  uint64_t stored_size = 0;  // bytes there: `size` when stored (torch.save's way), else deflated
  bool deflated = false;
};

// Every entry of the archive's central directory (zip64 included), keyed by the entry name without its
// leading top-level folder ("archive/data/0" -> "data/0"), as the checkpoint's pickle names
// records. Reads only the directory, which zip keeps at the end of the file, so a truncated download
// fails here. Malformed directories, entries outside the first entry's top-level folder (torch.save puts
// every record in one), two entries of one name and entries whose data would lie outside the file are a
// u3d::Error naming the file. Each record's data lies inside the file, before the directory.
std::map<std::string, ZipRecord> zip_records(const std::filesystem::path& path);

// Standard (zip / zlib) CRC-32, libdeflate's (carry-less multiplication where the CPU has it).
uint32_t crc32_of(const void* data, size_t size);

}  // namespace u3d::nn
