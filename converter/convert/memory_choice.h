// How much memory a conversion takes when no --memory-limit is given.
//
// Every conversion runs the same passes within a memory limit (streaming_convert.h): the limit sizes their
// batches, voxel ranges, order chunks and buffers, and a larger one buys fewer passes over the source and more
// ordering threads, never different bytes. Without a limit the conversion takes about the source's size: on
// 1M-streamline TCKs (2 cores) that is where one range of voxels, held in memory, is ordered on every thread
// (a 690 MB TCK: 3.4 s within 768 MiB, 4.8-5.0 s within 512 MiB, where its largest voxel's sort buffers
// leave room for one ordering thread). Never more than half of what is available (format/base/memory_available.h),
// so that a source larger than the memory streams within what there is.
#pragma once

#include <cstdint>
#include <optional>

namespace vxl {

// The limit for a TCK source of `source_bytes` (the file's size):
// 9/8 of it, at least 256 MiB and at most 6 GiB, but at most half of `available` (unknown: 1 GiB is assumed)
// and never under 64 MiB.
std::uint64_t default_memory_limit(std::uint64_t source_bytes, std::optional<std::uint64_t> available);

// The most a chosen limit takes of `available`: half, at least 64 MiB. A chosen limit too small for some part of
// the work is raised up to this. It is also the limit for a source already read whole (a format that does not
// stream, or TCK with TSF values): its passes take what they need of it (batches, buffers) and hold no copy of the
// source; a smaller default would refuse sources that it takes no more memory to convert.
std::uint64_t largest_chosen_memory_limit(std::optional<std::uint64_t> available);

// Whether `available` memory made the default limit smaller than the source wants (then the conversion
// reads it more times, and the programs say so).
bool limited_by_available_memory(std::uint64_t source_bytes, std::optional<std::uint64_t> available);

}  // namespace vxl
