#pragma once
// Output files are never left half-written: writers produce a temporary file beside the target and
// rename it into place only after the write succeeded.
#include <filesystem>
#include <functional>

namespace u3d {

// Calls write(tmp_path) with a temporary path in the target's folder, then renames tmp_path to path.
// On any exception the temporary file is removed and the exception propagates. Fails with a clear
// Error when the folder does not exist or is not writable.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& tmp_path)>& write);

// Creates dir (and parents) or throws Error naming it; succeeds if it already exists.
void ensure_directory(const std::filesystem::path& dir);

}  // namespace u3d
