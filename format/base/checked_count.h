// Arithmetic on counts read from a file. A count is whatever the file says, up to 2^64 - 1, so a product
// such as 3 x NumberOfPoints or a sum of cell counts can wrap and then pass a size check it should fail.
// Every reader multiplies and adds file-given counts through these.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "format/base/error.h"

namespace vxl {

// a x b and a + b, or nothing when the result does not fit in 64 bits.
inline std::optional<std::uint64_t> count_product(std::uint64_t a, std::uint64_t b) {
  std::uint64_t r = 0;
  if (__builtin_mul_overflow(a, b, &r)) return std::nullopt;
  return r;
}
inline std::optional<std::uint64_t> count_sum(std::uint64_t a, std::uint64_t b) {
  std::uint64_t r = 0;
  if (__builtin_add_overflow(a, b, &r)) return std::nullopt;
  return r;
}

// The same, refusing the file (vxl::Error, Input: exit 3) when the result does not fit: the message names
// `file`, `offset` when known, and says that `what` (a b or a + b) overflows.
inline std::uint64_t checked_product(std::uint64_t a, std::uint64_t b, const std::string& file,
                                     std::optional<std::uint64_t> offset, const std::string& what) {
  if (const auto r = count_product(a, b)) return *r;
  fail_input(file, offset, what + ": " + std::to_string(a) + " x " + std::to_string(b) + " does not fit in 64 bits");
}
inline std::uint64_t checked_sum(std::uint64_t a, std::uint64_t b, const std::string& file,
                                 std::optional<std::uint64_t> offset, const std::string& what) {
  if (const auto r = count_sum(a, b)) return *r;
  fail_input(file, offset, what + ": " + std::to_string(a) + " + " + std::to_string(b) + " does not fit in 64 bits");
}

}  // namespace vxl
