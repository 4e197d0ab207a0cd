// How much memory a conversion may take without a --memory-limit, and when to stream instead.
//
// A conversion in memory holds the source's points, the voxel blocks and the orders at once: its peak is
// about twice the TCK's size (1M synthetic streamlines: 1.36 GB for a 690 MB TCK), estimated at three times
// for a margin. When that estimate does not fit in what is available (format/base/memory_available.h),
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
