#pragma once
// What `unique3d batch` runs on: the objects of a batch, each a photo (run through `generate`) or a view
// folder (run through `reconstruct`), with the unique name its output folder takes. INPUTS is a folder
// of photos and/or view folders, or a text file listing them one per line (docs/cluster.md).
#include <filesystem>
#include <string>
#include <vector>

namespace u3d {

enum class BatchMode { Generate, Reconstruct };

// "generate" / "reconstruct".
const char* batch_mode_name(BatchMode mode);

struct BatchInput {
  std::filesystem::path path;  // the photo or the view folder
  std::string name;            // its output folder's name, unique in the batch
  BatchMode mode = BatchMode::Reconstruct;
};

// The objects of INPUTS, sorted by name (the file system's listing order plays no part):
//   a folder: each photo in it (.png, .jpg, .jpeg) and each sub-folder holding a view set
//     (front_rgb.png ...); hidden entries (".name") are passed over, other files are skipped with a
//     progress message, and a sub-folder without a view set is an Error naming its missing file;
//   a file: one photo or view folder per line, relative to the file's folder unless absolute; blank
//     lines and "#" comments are passed over; a line naming nothing usable is an Error with its number.
// Names are the photo's stem or the folder's name, with characters other than letters, digits, '-',
// '_' and '.' replaced by '_' (and no leading '.'). Inputs that share a name each get the suffix
// "-" + 8 hex digits of the hash of their path as listed (relative to INPUTS), so the name depends on
// the input itself, not on the order of the listing. An Error when INPUTS holds no object.
std::vector<BatchInput> list_batch_inputs(const std::filesystem::path& inputs);

// The naming rule above on inputs already found; `listed` are their paths as listed, used for the
// suffixes. Exposed for the tests.
std::vector<BatchInput> name_batch_inputs(const std::vector<std::filesystem::path>& paths,
                                          const std::vector<std::string>& listed, const std::vector<BatchMode>& modes);

}  // namespace u3d
