#include "server/zip_archive.h"

#include <sys/stat.h>
#include <zip.h>

#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"

namespace u3d::server {
namespace {

struct ZipCloser {
  void operator()(zip_t* z) const { zip_discard(z); }
};
struct ZipFileCloser {
  void operator()(zip_file_t* f) const { zip_fclose(f); }
};

// A name that would leave the folder it was unpacked into: absolute, or with a ".." part.
bool escapes(const std::string& name) {
  if (name.empty() || name[0] == '/' || name[0] == '\\') return true;
  size_t start = 0;
  while (start <= name.size()) {
    size_t end = name.find_first_of("/\\", start);
    if (end == std::string::npos) end = name.size();
    if (name.compare(start, end - start, "..") == 0 && end - start == 2) return true;
    start = end + 1;
  }
  return false;
}

}  // namespace

std::vector<ZipEntry> read_zip(const std::string& bytes, const ZipLimits& limits) {
  zip_error_t error;
  zip_error_init(&error);
  zip_source_t* source = zip_source_buffer_create(bytes.data(), bytes.size(), 0, &error);
  require(source != nullptr, "cannot read the zip: " + std::string(zip_error_strerror(&error)));
  std::unique_ptr<zip_t, ZipCloser> archive(zip_open_from_source(source, ZIP_RDONLY | ZIP_CHECKCONS, &error));
  if (!archive) {
    zip_source_free(source);
    const std::string reason = zip_error_strerror(&error);
    zip_error_fini(&error);
    throw Error("cannot read the zip: " + reason);
  }
  zip_error_fini(&error);

  const zip_int64_t count = zip_get_num_entries(archive.get(), 0);
  require(count >= 0 && size_t(count) <= limits.max_entries,
          "the zip holds " + std::to_string(count) + " entries; at most " + std::to_string(limits.max_entries) +
              " are accepted");
  std::vector<ZipEntry> entries;
  size_t total = 0;
  for (zip_uint64_t i = 0; i < zip_uint64_t(count); ++i) {
    zip_stat_t stat;
    require(zip_stat_index(archive.get(), i, 0, &stat) == 0 && (stat.valid & ZIP_STAT_NAME),
            "cannot read entry " + std::to_string(i) + " of the zip");
    const std::string name = stat.name;
    require(!escapes(name), "the zip holds '" + name + "', a name outside its folder");
    zip_uint8_t opsys = 0;
    zip_uint32_t attributes = 0;
    if (zip_file_get_external_attributes(archive.get(), i, 0, &opsys, &attributes) == 0 && opsys == ZIP_OPSYS_UNIX) {
      const mode_t mode = attributes >> 16;
      require(!S_ISLNK(mode), "the zip holds '" + name + "', a symbolic link");
    }
    if (!name.empty() && (name.back() == '/' || name.back() == '\\')) continue;  // a folder

    std::unique_ptr<zip_file_t, ZipFileCloser> file(zip_fopen_index(archive.get(), i, 0));
    require(file != nullptr, "cannot read '" + name + "' in the zip: " + zip_strerror(archive.get()));
    ZipEntry entry{name, {}};
    char buffer[1 << 16];
    for (;;) {
      const zip_int64_t n = zip_fread(file.get(), buffer, sizeof buffer);
      require(n >= 0, "cannot read '" + name + "' in the zip: " + zip_file_strerror(file.get()));
      if (n == 0) break;
      total += size_t(n);
      require(total <= limits.max_total_bytes, "the zip's files hold more than " +
                                                   std::to_string(limits.max_total_bytes >> 20) + " MiB");
      entry.data.append(buffer, size_t(n));
    }
    entries.push_back(std::move(entry));
  }
  return entries;
}

void write_zip(const std::filesystem::path& path,
               const std::vector<std::pair<std::string, std::filesystem::path>>& files) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    int code = 0;
    std::unique_ptr<zip_t, ZipCloser> archive(zip_open(tmp.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code));
    require(archive != nullptr, "cannot create " + path.string());
    for (const auto& [name, file] : files) {
      zip_source_t* source = zip_source_file(archive.get(), file.c_str(), 0, -1);
      require(source != nullptr, "cannot add " + file.string() + " to " + path.string());
      if (zip_file_add(archive.get(), name.c_str(), source, ZIP_FL_ENC_UTF_8) < 0) {
        zip_source_free(source);
        throw Error("cannot add " + file.string() + " to " + path.string() + ": " + zip_strerror(archive.get()));
      }
    }
    zip_t* z = archive.release();
    if (zip_close(z) != 0) {
      const std::string reason = zip_strerror(z);
      zip_discard(z);
      throw Error("cannot write " + path.string() + ": " + reason);
    }
  });
}

}  // namespace u3d::server
