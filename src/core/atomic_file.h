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

// Calls write(folder) to fill the output folder `dir`. When `dir` does not exist yet, `folder` is a
// temporary sibling that is renamed to `dir` only after write() returned, and removed on any exception,
// so a failed run leaves no folder behind; an existing `dir` is written in place (each file atomically
// by its writer).
void write_folder_atomically(const std::filesystem::path& dir,
                             const std::function<void(const std::filesystem::path& folder)>& write);

// Whether something is at `path` (following symlinks). A path that cannot be checked (a symlink loop,
// a folder without permission) is an Error naming it; a missing one is just false.
bool path_exists(const std::filesystem::path& path);

}  // namespace u3d
