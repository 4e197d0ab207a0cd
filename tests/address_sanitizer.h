// Whether this translation unit is built with AddressSanitizer, for the few tests whose measure (address
// space, resident memory) ASan's shadow memory and allocator make meaningless. GCC defines
// __SANITIZE_ADDRESS__; Clang 14 does not and answers __has_feature(address_sanitizer) instead.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define VOXLINES_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VOXLINES_ADDRESS_SANITIZER 1
#endif
#endif

namespace vxl::test {
#if defined(VOXLINES_ADDRESS_SANITIZER)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
}  // namespace vxl::test
