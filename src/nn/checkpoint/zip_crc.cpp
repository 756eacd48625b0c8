#include "nn/checkpoint/zip_crc.h"

#include <libdeflate.h>

#include <algorithm>
#include <fstream>
#include <vector>

#include "core/error.h"

namespace u3d::nn {
namespace {

uint64_t le(const std::string& b, size_t pos, int n) {
  uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | uint8_t(b[pos + i]);
  return v;
}

std::string read_at(std::ifstream& in, uint64_t offset, uint64_t size, const std::string& source) {
  std::string buf(size, '\0');
  in.clear();
  in.seekg(std::streamoff(offset));
  in.read(buf.data(), std::streamsize(size));
  require(in.gcount() == std::streamsize(size), source + ": zip directory points outside the file");
  return buf;
}

}  // namespace

uint32_t crc32_of(const void* data, size_t size) { return libdeflate_crc32(0, data, size); }

std::map<std::string, ZipRecord> zip_records(const std::filesystem::path& path) {
  const std::string source = path.string();
  std::ifstream in(path, std::ios::binary);
  require(bool(in), "cannot open " + source);
  const uint64_t file_size = std::filesystem::file_size(path);
  auto bad = [&](const std::string& what) {
    return Error(source + ": corrupt or truncated zip archive (" + what + ")");
  };

  // End of central directory record: 22 bytes plus a comment of up to 64 KiB, at the end of the file.
  const uint64_t tail_size = std::min<uint64_t>(file_size, 22 + 65535);
  const std::string tail = read_at(in, file_size - tail_size, tail_size, source);
  const size_t eocd = tail.rfind(std::string("PK\x05\x06", 4));
  if (eocd == std::string::npos || eocd + 22 > tail.size()) throw bad("no end-of-directory record");
  uint64_t entries = le(tail, eocd + 10, 2);
  uint64_t dir_size = le(tail, eocd + 12, 4);
  uint64_t dir_offset = le(tail, eocd + 16, 4);
  if (entries == 0xffff || dir_size == 0xffffffff || dir_offset == 0xffffffff) {
    // zip64: a locator just before the record points to the zip64 end-of-directory record.
    if (eocd < 20 || tail.compare(eocd - 20, 4, std::string("PK\x06\x07", 4)) != 0) throw bad("no zip64 locator");
    const std::string z64 = read_at(in, le(tail, eocd - 20 + 8, 8), 56, source);
    if (z64.compare(0, 4, std::string("PK\x06\x06", 4)) != 0) throw bad("no zip64 end-of-directory record");
    entries = le(z64, 32, 8);
    dir_size = le(z64, 40, 8);
    dir_offset = le(z64, 48, 8);
  }
  if (dir_offset > file_size || dir_size > file_size - dir_offset) throw bad("directory outside the file");

  const std::string dir = read_at(in, dir_offset, dir_size, source);
  std::map<std::string, ZipRecord> records;
  std::string folder;
  size_t pos = 0;
  for (uint64_t i = 0; i < entries; ++i) {
    if (pos + 46 > dir.size() || dir.compare(pos, 4, std::string("PK\x01\x02", 4)) != 0) throw bad("bad entry header");
    const auto crc = uint32_t(le(dir, pos + 16, 4));
    const size_t name_len = le(dir, pos + 28, 2), extra_len = le(dir, pos + 30, 2), comment_len = le(dir, pos + 32, 2);
    if (pos + 46 + name_len > dir.size()) throw bad("entry name outside the directory");
    if (pos + 46 + name_len + extra_len > dir.size()) throw bad("entry fields outside the directory");
    const std::string name = dir.substr(pos + 46, name_len);
    uint64_t size = le(dir, pos + 24, 4), compressed = le(dir, pos + 20, 4), offset = le(dir, pos + 42, 4);
    // zip64: the extra field 0x0001 holds, in this order, each of the three that is 0xffffffff here.
    for (size_t e = pos + 46 + name_len; e + 4 <= pos + 46 + name_len + extra_len;) {
      const uint64_t id = le(dir, e, 2), len = le(dir, e + 2, 2);
      if (e + 4 + len > pos + 46 + name_len + extra_len) throw bad("extra field outside its entry");
      if (id == 1) {
        size_t f = e + 4;
        for (uint64_t* v : {&size, &compressed, &offset}) {
          if (*v != 0xffffffff) continue;
          if (f + 8 > e + 4 + len) throw bad("short zip64 extra field");
          *v = le(dir, f, 8);
          f += 8;
        }
      }
      e += 4 + len;
    }
    if (offset > dir_offset || compressed > dir_offset - offset)
      throw bad("entry " + name + " lies outside the file (truncated download?)");
    // The size a deflated record is inflated into: stored (torch.save's way) or deflated data cannot hold
    // more than this, so a larger claim is corrupt and would only allocate memory for nothing.
    const uint64_t method = le(dir, pos + 10, 2);
    if (method != 0 && method != 8) throw bad("entry " + name + " uses compression method " + std::to_string(method));
    if (method == 0 ? size != compressed : size / 1032 > compressed)
      throw bad("entry " + name + " claims " + std::to_string(size) + " bytes from " + std::to_string(compressed));
    // The entry's local header, in front of its data, must be there and name the same entry.
    if (dir_offset - offset - compressed < 30) throw bad("entry " + name + " has no room for its local header");
    const std::string local = read_at(in, offset, 30, source);
    const uint64_t local_name_len = le(local, 26, 2), local_extra_len = le(local, 28, 2);
    if (local.compare(0, 4, std::string("PK\x03\x04", 4)) != 0 || local_name_len != name_len ||
        read_at(in, offset + 30, name_len, source) != name)
      throw bad("entry " + name + " does not match its local header");
    if (dir_offset - offset - compressed < 30 + local_name_len + local_extra_len)
      throw bad("entry " + name + " lies outside the file (truncated download?)");
    // torch.save puts every record in one top-level folder, named after the checkpoint.
    const size_t slash = name.find('/');
    if (slash == std::string::npos) throw bad("entry " + name + " is not inside a folder");
    if (i == 0) folder = name.substr(0, slash + 1);
    if (name.compare(0, slash + 1, folder) != 0) throw bad("entry " + name + " is outside the folder " + folder);
    const ZipRecord record{crc, size, offset + 30 + local_name_len + local_extra_len, compressed, method == 8};
    if (!records.emplace(name.substr(slash + 1), record).second) throw bad("two entries named " + name);
    pos += 46 + name_len + extra_len + comment_len;
  }
  return records;
}

}  // namespace u3d::nn
