// An unpack's positions (spec/vxlz-package-v2.md §7 steps 3-4). A packed .vxl's words depend on each voxel's tight
// bounds, known only once every chunk is decoded: either the decoded positions are kept as floats until then (12 bytes
// a vertex, more than the packed .vxl itself: 768 MB beside a 781 MB file for 1M streamlines, 5 GB for 10M), or the
// chunks are decoded twice, the first time for the bounds (and the voxline ends and the lengths), the second to write
// the words (about a tenth more time; what it holds is small beside the floats: a packer a voxel, and the steps of the
// few streamlines the chunks cut, 8 bytes a point, until they are joined). A float32 .vxl gets the decoded positions as
// they are, decoded once. Chunks are decoded side by side.
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "converter/convert/voxelize.h"
#include "converter/package/unpack_structure.h"
#include "format/vxl_positions.h"
#include "format/vxl_stream_writer.h"
#include "format/vxlz_package.h"

namespace vxl {

// The first pass: sets the tight bounds of s.voxels (zeros as +0, spec §5.3), marks the last vertex of every voxline
// in `ends` and writes each streamline's SLEN length (stored_length_of of its points, synthetic face points left out)
// into `lengths`, which holds one per streamline; with `keep`, also every vertex's decoded position there (3 floats a
// vertex, VERT's order). `progress` gets the fraction of chunks done. Throws vxl::Error (Input) for a damaged chunk, or
// where the chunks the streamlines need are not all there.
void scan_positions(const VxlzFile& f, UnpackStructure& s, VoxlineEnds& ends, std::span<float> lengths,
                    unsigned threads, const std::function<void(double)>& progress, float* keep = nullptr);

// The packed words of the positions scan_positions kept, once the bounds are set, into `words` (VERT's payload).
// Returns the largest packing error bound of the voxels.
double pack_kept_positions(const UnpackStructure& s, std::span<float> kept, const VoxlineEnds& ends,
                           std::span<std::uint32_t> words, unsigned threads);

// Or the second pass, once the bounds are set: the packed words (end bits from `ends`) decoded again into `words`
// (VERT's payload). Returns the largest packing error bound of the voxels.
double write_positions(const VxlzFile& f, const UnpackStructure& s, const VoxlineEnds& ends,
                       std::span<std::uint32_t> words, unsigned threads, const std::function<void(double)>& progress);

// Or the second pass without VERT in memory (a packed .vxl's whole unpack): the chunks decoded again in shipping
// order on this thread, each voxline's words appended to its (voxel, depth) block of `out`'s VERT through a region
// writer of the block's own (staged `staging_bytes` at a time, the staging let go once the block is complete), which
// the shipping order fills from its first vertex on (a depth's streamlines in order, spec §5.1; a voxel's block holds
// each depth's voxlines so, §5.12). VERT is then read back for the orders. Returns the largest packing error bound of
// the voxels. Throws vxl::Error (Input) where the package's points do not fill a block in order or to its end.
double write_positions_in_blocks(const VxlzFile& f, const UnpackStructure& s, const VoxlineEnds& ends,
                                 VxlStreamWriter& out, std::uint64_t staging_bytes,
                                 const std::function<void(double)>& progress);

// The most memory the blocks' stagings of write_positions_in_blocks hold at once, with stagings of `staging_bytes`
// (DirectRegionWriter::staging_size of each open block): in streamline order every block of every voxel is open from
// its first point to its last; in level order only the blocks one shipped depth fills (`pack`: the package's order and
// levels; s.level_count at least its levels).
std::uint64_t open_block_staging_bytes(const UnpackStructure& s, const PackSection& pack, std::uint64_t staging_bytes);

}  // namespace vxl
