#pragma once
// Whether the tests were built with AddressSanitizer (scripts/test.sh --sanitize). A few tests measure
// what ASan changes by design, the allocator (it replaces glibc's malloc) and speed (it runs several
// times slower); they skip there.
#if defined(__SANITIZE_ADDRESS__)
#define U3D_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define U3D_UNDER_ASAN 1
#endif
#endif

namespace u3d::test {
#ifdef U3D_UNDER_ASAN
inline constexpr bool kUnderAsan = true;
#else
inline constexpr bool kUnderAsan = false;
#endif
}  // namespace u3d::test
