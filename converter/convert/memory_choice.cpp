#include "converter/convert/memory_choice.h"

#include <algorithm>

namespace vxl {
namespace {

constexpr double kPeakPerSourceByte = 3.0;  // measured 2.5-2.6, rounded up
constexpr std::uint64_t kMinimumLimit = 64ull << 20;
// More gains little: streaming's extra passes are cheap next to the work, and a machine's other jobs keep
// the rest.
constexpr std::uint64_t kMaximumLimit = 6ull << 30;

}  // namespace

std::uint64_t in_memory_estimate(std::uint64_t source_bytes) {
  return static_cast<std::uint64_t>(kPeakPerSourceByte * double(source_bytes));
}

std::optional<std::uint64_t> automatic_memory_limit(std::uint64_t source_bytes, std::uint64_t available) {
  // Half, not all: a conversion that fills the machine pushes out everything else (and, at 90 %, the 10M
  // set converted in memory peaked at 19.6 GB of 24 GB).
  if (double(in_memory_estimate(source_bytes)) <= 0.5 * double(available)) return std::nullopt;
  return std::clamp(available / 2, kMinimumLimit, kMaximumLimit);
}

}  // namespace vxl
