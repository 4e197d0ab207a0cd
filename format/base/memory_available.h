// How much memory this process can take: what the machine and its cgroup leave, and what bounds it, for
// the choices that depend on it (a conversion's, converter/convert/memory_choice.h; the viewer's) and for
// the messages of a refusal.
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

}  // namespace vxl
