#pragma once
// Skips that cannot go unnoticed. A test that needs what only some machines have (native bf16 kernels,
// the real ISNet matting model fetched from npm) skips with its reason elsewhere, and fails instead
// where the environment says the thing is there: scripts/test.sh sets UNIQUE3D_REQUIRE_BF16=1 when
// /proc/cpuinfo lists avx512_bf16, and UNIQUE3D_REQUIRE_REAL_ISNET=1 when
// scripts/fetch_imgly_isnet.sh has the model, so a broken detection or a lost file is a failure there.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "nn/precision.h"

namespace u3d::nn::test {

// Whether the environment variable is set to 1.
inline bool required_by_environment(const char* variable) {
  const char* value = std::getenv(variable);
  return value != nullptr && std::strcmp(value, "1") == 0;
}

}  // namespace u3d::nn::test

// In a test body: when `available` is false, fails if the environment variable `variable` is 1, else
// skips; either way with `reason` (a stream expression).
#define U3D_SKIP_UNLESS_AVAILABLE(available, variable, reason)                                         \
  do {                                                                                                 \
    if (!(available)) {                                                                                \
      if (::u3d::nn::test::required_by_environment(variable)) FAIL() << variable "=1, but " << reason; \
      GTEST_SKIP() << reason << " (" variable "=1 makes this a failure)";                              \
    }                                                                                                  \
  } while (false)

// The bf16 tests' tolerances, and the oneDNN bf16 path, assume native bf16 kernels.
#define U3D_SKIP_UNLESS_BF16_KERNELS()                                                  \
  U3D_SKIP_UNLESS_AVAILABLE(::u3d::nn::cpu_has_bf16_kernels(), "UNIQUE3D_REQUIRE_BF16", \
                            "this CPU has no native bf16 kernels (avx512_bf16)")
