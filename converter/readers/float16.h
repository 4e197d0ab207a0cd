// IEEE 754 binary16 ("half") -> binary32 conversion. Every half value is exactly representable as a
// float, so the conversion is exact: zeros, subnormals, infinities and NaNs (payload kept) included.
// Done with integer bit manipulation so it needs no compiler support for _Float16.
#pragma once

#include <bit>
#include <cstdint>

namespace vxl {

constexpr float half_to_float(std::uint16_t h) {
  const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
  const std::uint32_t exponent = (h >> 10) & 0x1Fu;
  std::uint32_t mantissa = h & 0x3FFu;
  std::uint32_t bits;
  if (exponent == 0x1Fu) {
    // Inf / NaN: all-ones exponent; the 10 mantissa bits move to the top of the 23.
    bits = sign | 0x7F800000u | (mantissa << 13);
  } else if (exponent != 0) {
    // Normal: rebias the exponent from 15 to 127.
    bits = sign | ((exponent + (127 - 15)) << 23) | (mantissa << 13);
  } else if (mantissa == 0) {
    bits = sign;  // signed zero
  } else {
    // Subnormal half (value = mantissa * 2^-24) is a normal float: shift the leading 1 into the
    // implicit position and lower the exponent by one per shift.
    std::uint32_t e = 127 - 15 + 1;
    while ((mantissa & 0x400u) == 0) {
      mantissa <<= 1;
      --e;
    }
    bits = sign | (e << 23) | ((mantissa & 0x3FFu) << 13);
  }
  return std::bit_cast<float>(bits);
}

}  // namespace vxl
