// A float's bits, as std::bit_cast gives them (which the web build's C++ library lacks).
#pragma once

#include <cstdint>
#include <cstring>

namespace vxl {

inline std::uint32_t float_bits(float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
}

}  // namespace vxl
