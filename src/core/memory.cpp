#include "core/memory.h"

#include <malloc.h>

namespace u3d {

void keep_freed_memory_for_reuse() {
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, -1);  // glibc reads it as size_t: never trim
}

}  // namespace u3d
