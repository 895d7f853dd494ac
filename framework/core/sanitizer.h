#pragma once
/// SPEC2FAB_ASAN is 1 in a build under AddressSanitizer, by GCC or clang:
/// GCC defines __SANITIZE_ADDRESS__, clang (before 16) says so only through
/// __has_feature — a check of the GCC macro alone is silently false there.

#if defined(__SANITIZE_ADDRESS__)
#define SPEC2FAB_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SPEC2FAB_ASAN 1
#endif
#endif
#ifndef SPEC2FAB_ASAN
#define SPEC2FAB_ASAN 0
#endif
