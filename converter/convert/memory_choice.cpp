#include "converter/convert/memory_choice.h"

#include <algorithm>

namespace vxl {
namespace {

constexpr std::uint64_t kMiB = 1ull << 20;
constexpr std::uint64_t kSmallestDefault = 256 * kMiB;
// More gains little: a larger source's extra passes are cheap next to the work, and a machine's other jobs
// keep the rest.
constexpr std::uint64_t kLargestDefault = 6ull << 30;
constexpr std::uint64_t kMinimumLimit = 64 * kMiB;
constexpr std::uint64_t kAssumedAvailable = 1ull << 30;

std::uint64_t wanted(std::uint64_t source_bytes) {
  return std::clamp(source_bytes / 8 * 9, kSmallestDefault, kLargestDefault);
}

std::uint64_t ceiling(std::optional<std::uint64_t> available) {
  // Half, not all: a conversion that fills the machine pushes out everything else.
  return std::max(kMinimumLimit, available.value_or(kAssumedAvailable) / 2);
}

}  // namespace

std::uint64_t default_memory_limit(std::uint64_t source_bytes, std::optional<std::uint64_t> available) {
  return std::min(wanted(source_bytes), ceiling(available));
}

std::uint64_t largest_chosen_memory_limit(std::optional<std::uint64_t> available) { return ceiling(available); }

bool limited_by_available_memory(std::uint64_t source_bytes, std::optional<std::uint64_t> available) {
  return ceiling(available) < wanted(source_bytes);
}

}  // namespace vxl
