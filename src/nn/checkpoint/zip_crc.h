#pragma once
// CRC-32 checks for the records of a zip archive. libtorch's zip reader does not verify CRCs, so a
// flipped byte inside a torch.save checkpoint would otherwise load as a silently wrong weight.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace u3d::nn {

// The CRC-32 of every entry, read from the archive's central directory (zip64 included), keyed by the
// entry name without its leading top-level folder ("archive/data/0" -> "data/0"), as libtorch's
// PyTorchStreamReader names records. Malformed directories are a u3d::Error naming the file.
std::map<std::string, uint32_t> zip_record_crcs(const std::filesystem::path& path);

// Standard (zip / zlib) CRC-32.
uint32_t crc32_of(const void* data, size_t size);

}  // namespace u3d::nn
