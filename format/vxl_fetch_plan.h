// Reading a .vxl file by byte ranges (the web viewer over HTTP Range requests): which bytes open() needs, which
// bytes draw a level of detail (spec §5.12), and what is left. A reader holds a buffer of the file's size,
// fills the ranges as they arrive, opens it once ranges_to_open's are in, and draws a level once that level's
// are: nothing else in the buffer is read until then, so the rest may come later (or never, for a preview).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "format/vxl_file.h"

namespace vxl {

struct ByteRange {
  std::uint64_t begin = 0, end = 0;  // [begin, end)
  bool operator==(const ByteRange&) const = default;
};

// The largest file a reader in 32-bit WebAssembly holds (its memory is 4 GiB at most), with room left for the
// viewer beside it: the web viewer draws a larger .vxl from its coarser levels (vxl_level_image.h), and cannot unpack
// a package into a larger one.
inline constexpr std::uint64_t kWebMaxFileBytes = (std::uint64_t(1) << 32) - (std::uint64_t(1) << 28);

// Enough of a file's first bytes for the header and the largest section table (spec §3, §4).
inline constexpr std::uint64_t kSectionTableBytesMax = sizeof(FileHeader) + kVxlMaxSections * sizeof(SectionEntry);

// What open() reads, from the file's first bytes (at least the header and the section table, checked as open()
// checks them; throws vxl::Error as it does): the header and table, every section whole but the per-point,
// per-voxline and per-streamline ones (VERT, ORDB/ORDR, VXLN, STRM, SLEN), and only the heads of VXIX (its
// voxel list starts) and of the value sets (their names). Sorted, disjoint, adjacent ones merged.
std::vector<ByteRange> ranges_to_open(const std::string& path, std::span<const std::uint8_t> first,
                                      std::uint64_t file_size);

// What drawing `level` of every voxel reads: the prefix of its block in VERT and that level's orders (spec
// §5.4, §5.5). Sorted, and merged where less than `gap` bytes lie between two.
std::vector<ByteRange> ranges_of_level(const VxlFile& file, std::uint32_t level, std::uint64_t gap);
// The same for voxels [voxel_first, voxel_first + voxel_count) of the voxel table only (a viewer's texture span).
std::vector<ByteRange> ranges_of_voxels(const VxlFile& file, std::uint32_t level, std::uint32_t voxel_first,
                                        std::uint32_t voxel_count, std::uint64_t gap);

// Asks the system to read what drawing `level` of `file` reads (ranges_of_level) ahead, in file order: a viewer about
// to upload a level of a file not in the page cache then waits for one batch of reads, not for a page fault each. At
// most a quarter of the available memory is asked for (the first of the level's ranges): pages read ahead past what
// memory holds would be dropped before the upload reaches them, and read twice.
void read_ahead_level(const VxlFile& file, std::uint32_t level);

// The first `budget` bytes of `ranges` (sorted and disjoint), the last range cut where the budget ends.
std::vector<ByteRange> ranges_prefix(std::span<const ByteRange> ranges, std::uint64_t budget);

// Sorts `ranges` and merges those that overlap or lie less than `gap` bytes apart.
std::vector<ByteRange> merge_ranges(std::vector<ByteRange> ranges, std::uint64_t gap);

// [0, size) less `held` (sorted and disjoint, as the functions above give them).
std::vector<ByteRange> ranges_missing(std::span<const ByteRange> held, std::uint64_t size);

// Whether every byte of `wanted` lies in `held` (as merge_ranges(..., 0) gives it: sorted, disjoint, none touching);
// a binary search of `held` per range of `wanted`.
bool ranges_held(std::span<const ByteRange> wanted, std::span<const ByteRange> held);

// The bytes in both `a` and `b` (each sorted and disjoint), in one pass over both.
std::vector<ByteRange> ranges_intersection(std::span<const ByteRange> a, std::span<const ByteRange> b);

}  // namespace vxl
