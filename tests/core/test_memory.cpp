// The allocator set-up: freed large blocks stay mapped and are reused without page faults.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cstdlib>
#include <cstring>

#include "core/memory.h"
#include "core/sanitizer.h"

namespace {

long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// Allocates and touches `bytes`, frees them; returns the page faults this took.
long faults_to_fill_a_fresh_block(size_t bytes) {
  const long before = minor_faults();
  void* block = std::malloc(bytes);
  std::memset(block, 1, bytes);
  asm volatile("" : : "r"(block) : "memory");  // the compiler may not drop the unused block
  std::free(block);
  return minor_faults() - before;
}

}  // namespace

TEST(Memory, FreedLargeBlocksAreReusedWithoutPageFaults) {
  if (u3d::kUnderAsan) GTEST_SKIP() << "ASan replaces glibc's allocator, whose settings this test checks";
  u3d::keep_freed_memory_for_reuse();
  const size_t bytes = size_t{64} << 20;  // above glibc's largest mmap threshold (32 MB)
  faults_to_fill_a_fresh_block(bytes);    // maps the pages once
  const long pages = static_cast<long>(bytes / 4096);
  // Without the set-up every one of the 16384 pages faults again.
  EXPECT_LT(faults_to_fill_a_fresh_block(bytes), pages / 10);
}

