#pragma once
// SHA-256 of a batch object's input files, so that a re-run can tell whether an object it finished
// before still has the same input (done.json records it; docs/cluster.md).
#include <filesystem>
#include <string>

#include "batch/batch_inputs.h"

namespace u3d {

// Hex SHA-256 of a file's bytes; an Error naming the file when it cannot be read.
std::string sha256_file(const std::filesystem::path& path);

// The input's hash: a photo's SHA-256; for a view folder, the SHA-256 of the lines "<file> <sha256>\n"
// of its eight view images in view order (core/view_set.h), so renaming the folder changes nothing.
std::string input_hash(const BatchInput& input);

}  // namespace u3d
