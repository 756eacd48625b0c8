#pragma once
// Whether this build has AddressSanitizer (scripts/test.sh --sanitize). What ASan changes by design
// is kept out of its way: the networks' tensor allocator is not installed there (ASan watches the
// bounds of malloc's blocks, not of other mappings, nn/runtime.h), and the tests of the malloc
// settings (ASan replaces glibc's malloc) and of speed (it runs several times slower) skip.
// GCC defines __SANITIZE_ADDRESS__; clang answers __has_feature.
#if defined(__SANITIZE_ADDRESS__)
#define U3D_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define U3D_UNDER_ASAN 1
#endif
#endif

namespace u3d {
#ifdef U3D_UNDER_ASAN
inline constexpr bool kUnderAsan = true;
#else
inline constexpr bool kUnderAsan = false;
#endif
}  // namespace u3d
