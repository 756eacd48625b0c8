// The single translation unit that compiles tinygltf's implementation.
#define TINYGLTF_IMPLEMENTATION
#include "io/tinygltf.h"
