// How much memory a conversion may take without a --memory-limit, and when to stream instead.
//
// A conversion in memory holds the source's points, the voxel blocks and the orders at once: measured
// peaks are 2.5 to 2.6 times the TCK's size (1M synthetic streamlines: 1.4 GB for 539 MB; 10M: 17.3 GB for
// 6.9 GB). When that estimate does not fit in what is available (format/base/memory_available.h),
// `voxlines convert` and voxview stream the TCK (streaming_convert.h) within a limit that does, and say so
// (source_to_vxl.h).
#pragma once

#include <cstdint>
#include <optional>

namespace vxl {

// The estimated peak of a conversion in memory of a TCK source of `source_bytes` bytes.
std::uint64_t in_memory_estimate(std::uint64_t source_bytes);

// The --memory-limit to stream with when the estimate exceeds half of `available`: half of what is
// available, at least 64 MiB and at most 6 GiB; nullopt when converting in memory fits.
std::optional<std::uint64_t> automatic_memory_limit(std::uint64_t source_bytes, std::uint64_t available);

}  // namespace vxl
