// How much memory a conversion may take without a --memory-limit, and when to stream instead.
//
// A conversion in memory holds the source's points, the voxel blocks and the orders at once: measured
// peaks are 2.5 to 2.6 times the TCK's size (1M synthetic streamlines: 1.4 GB for 539 MB; 10M: 17.3 GB for
// 6.9 GB). When that estimate does not fit in what is available, `voxlines convert` streams the TCK
// (streaming_convert.h) within a limit that does, and says so.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace vxl {

// Bytes this process can use: the smaller of /proc/meminfo's MemAvailable and what the cgroup (a batch
// job's memory limit, e.g. Slurm's --mem) leaves: memory.max - memory.current (cgroup v2) or
// memory.limit_in_bytes - memory.usage_in_bytes (v1). VOXLINES_MEMORY_AVAILABLE=SIZE (as --memory-limit
// takes it) overrides all of them. nullopt when none can be read.
std::optional<std::uint64_t> available_memory();

// What bounds this process's memory, for a refusal's message: "the address-space limit (ulimit -v) of 4.0 GiB"
// when RLIMIT_AS is set, else "the 12.3 GiB of memory available" (available_memory), else "this machine's memory".
std::string memory_limit_text();

// The estimated peak of a conversion in memory of a TCK source of `source_bytes` bytes.
std::uint64_t in_memory_estimate(std::uint64_t source_bytes);

// The --memory-limit to stream with when the estimate exceeds half of `available`: half of what is
// available, at least 64 MiB and at most 6 GiB; nullopt when converting in memory fits.
std::optional<std::uint64_t> automatic_memory_limit(std::uint64_t source_bytes, std::uint64_t available);

}  // namespace vxl
