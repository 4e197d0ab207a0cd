// The value sets of a .vxlz package (spec/vxlz-package-v2.md §4.7): `PVAL`, the per-vertex values of
// the .vxl for every shipped point, and `SVAL`, the per-streamline values. Exact: each set is its float32
// bit patterns, deflated either as they are or as byte planes of their XOR with the previous value,
// whichever is smaller, so that unpacking gives back the very bits the .vxl held.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "format/vxlz_streams.h"

namespace vxl {

struct NamedValues {
  std::string name;  // at most 47 bytes (cut at a character boundary by the encoder, as in the .vxl)
  std::vector<float> values;
};

inline constexpr std::uint32_t kValueCodingPlain = 0;      // the float32 bit patterns, little-endian
inline constexpr std::uint32_t kValueCodingXorPlanes = 1;  // byte planes of bits_i XOR bits_{i-1}

// The section payload of 1..64 sets of equal length, each set deflated with the smaller coding (sets in
// parallel on up to `threads` threads; 0: all cores). Throws vxl::Error (Output) when zlib fails.
std::vector<std::uint8_t> encode_value_section(std::span<const NamedValues> sets, unsigned threads = 0);

// Decodes a payload that must hold sets of exactly `count` values; throws vxl::Error (Input naming the
// section and the byte offset; Unsupported for an unknown coding). Every size is checked against `count`
// and the payload's size before anything is allocated or inflated.
std::vector<NamedValues> decode_value_section(std::span<const std::uint8_t> payload, std::uint64_t count,
                                              const StreamContext& context, unsigned threads = 0);

}  // namespace vxl
