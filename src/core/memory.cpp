#include "core/memory.h"

#include <malloc.h>

namespace u3d {

namespace {
constexpr int kOwnMappingBytes = 256 << 20;
}  // namespace

void keep_freed_memory_for_reuse() {
  mallopt(M_MMAP_THRESHOLD, kOwnMappingBytes);  // a fixed threshold: glibc no longer raises it by itself
  mallopt(M_TRIM_THRESHOLD, -1);                // glibc reads it as size_t: never trim
}

void release_freed_memory() { malloc_trim(0); }

}  // namespace u3d
