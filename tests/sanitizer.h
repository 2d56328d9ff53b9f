// UPD_TEST_UNDER_ASAN is defined when the test is built under AddressSanitizer, by gcc
// (__SANITIZE_ADDRESS__) or by clang (__has_feature(address_sanitizer)): the few checks that
// measure the allocator or need operator new to throw are left out there.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define UPD_TEST_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UPD_TEST_UNDER_ASAN 1
#endif
#endif
