#pragma once
// Process-wide allocator set-up shared by the entry points (CLI, benches).
namespace u3d {

// Makes glibc's malloc keep freed memory in the process: no mmap for large blocks and no trimming of
// the heap. Both ISOMER (megabyte buffers every optimisation step) and the networks (tensors of tens
// of megabytes every layer) otherwise have their freed blocks unmapped and fault the same pages in
// again on the next step. The peak resident size is unchanged; the process just does not shrink
// after its largest step.
void keep_freed_memory_for_reuse();

}  // namespace u3d
