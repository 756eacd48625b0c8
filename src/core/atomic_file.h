#pragma once
// Output files are never left half-written: writers produce a temporary file beside the target and
// rename it into place only after the write succeeded. Also the checks of input paths that must end in
// an Error naming the path rather than a filesystem exception.
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

// Whether something is at `path` (following symlinks). A path that cannot be checked (a symlink loop,
// a folder without permission) is an Error naming it; a missing one is just false.
bool path_exists(const std::filesystem::path& path);

}  // namespace u3d
