// Writes the tiny stand-in model folder and the small object photo of the C++ generate tests
// (tests/pipeline/tiny_model_folder.h) for the Python module's generate tests:
//   make_tiny_models MODELS_DIR PHOTO.png
#include <cstdio>
#include <exception>

#include "pipeline/tiny_model_folder.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_tiny_models MODELS_DIR PHOTO.png\n");
    return 2;
  }
  try {
    u3d::testing::write_tiny_model_folder(argv[1]);
    u3d::testing::write_disk_photo(argv[2]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_tiny_models: %s\n", e.what());
    return 1;
  }
  return 0;
}
