#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <string>

#include "core/error.h"

namespace u3d {

namespace fs = std::filesystem;

namespace {

// Fills the temporary `tmp` with write(tmp) and renames it to `target`; on any exception removes
// `tmp` (a file or a folder) and rethrows, filesystem errors as an Error naming the target.
void write_then_rename(const fs::path& tmp, const fs::path& target, const std::function<void(const fs::path&)>& write) {
  std::error_code ec;
  try {
    write(tmp);
    fs::rename(tmp, target);
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(tmp, ec);
    throw Error("cannot write " + target.string() + ": " + e.code().message());
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

}  // namespace

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error("cannot write " + path.string() + ": folder " + dir.string() + " does not exist");
  if (access(dir.c_str(), W_OK) != 0) throw Error("cannot write " + path.string() + ": folder " + dir.string() + " is not writable");
  if (fs::is_directory(path, ec)) throw Error("cannot write " + path.string() + ": it is a folder");
  static std::atomic<int> counter{0};
  // Keep the extension last: OpenCV and friends pick the encoder from it.
  fs::path tmp = dir / ("." + path.stem().string() + ".tmp" + std::to_string(getpid()) + "_" +
                        std::to_string(counter++) + path.extension().string());
  write_then_rename(tmp, path, write);
}

void ensure_directory(const fs::path& dir) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) {
    if (access(dir.c_str(), W_OK) != 0) throw Error("output folder " + dir.string() + " is not writable");
    return;
  }
  fs::create_directories(dir, ec);
  if (ec) throw Error("cannot create output folder " + dir.string() + ": " + ec.message());
}

void write_folder_atomically(const fs::path& dir, const std::function<void(const fs::path&)>& write) {
  if (path_exists(dir)) {
    ensure_directory(dir);
    write(dir);
    return;
  }
  const fs::path parent = dir.parent_path().empty() ? fs::path(".") : dir.parent_path();
  ensure_directory(parent);
  const fs::path tmp = parent / ("." + dir.filename().string() + ".partial" + std::to_string(getpid()));
  std::error_code ec;
  fs::remove_all(tmp, ec);
  ensure_directory(tmp);
  write_then_rename(tmp, dir, write);
}

bool path_exists(const fs::path& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory)
    throw Error(path.string() + ": " + ec.message());
  return fs::exists(status);
}

}  // namespace u3d
