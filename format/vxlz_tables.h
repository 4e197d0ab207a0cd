// The exact part of a .vxlz package (spec/vxlz-package-v2.md §4): the voxel coordinates, the streamline
// and voxline tables and the groups as varint streams, and back. Decoding checks what each stream alone
// can tell (counts, ranges, order); the unpacker checks the rest against META (spec §8 step 6).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "format/vxl_layout.h"
#include "format/vxl_sections.h"
#include "format/vxlz_streams.h"

namespace vxl {

// Encoders: the raw (not yet deflated) stream bytes.
std::vector<std::uint8_t> encode_voxel_coords(std::span<const VoxelEntry> voxels);          // VOXC
std::vector<std::uint8_t> encode_streamline_voxlines(std::span<const std::uint64_t> strm);  // STRL (N + 1 entries in)
std::vector<std::uint8_t> encode_voxline_voxels(std::span<const VoxlineEntry> voxlines,     // VXLV
                                                std::span<const VoxelEntry> voxels);
std::vector<std::uint8_t> encode_voxline_counts(std::span<const VoxlineEntry> voxlines);  // VXLC
std::vector<std::uint8_t> encode_group_stream(std::span<const StreamlineGroup> groups);   // GRPS

// Decoders. Each throws vxl::Error (Input) naming the section unless the stream holds exactly `count`
// well-formed values (spec §8 steps 5-6).
// Coordinates in [0, grid_dims), strictly increasing in (z, y, x).
std::vector<std::array<std::int32_t, 3>> decode_voxel_coords(std::span<const std::uint8_t> stream, std::uint32_t count,
                                                             const std::int32_t grid_dims[3],
                                                             const StreamContext& context);
// The STRM table (N + 1 prefix sums), ending at `voxline_count`.
std::vector<std::uint64_t> decode_streamline_voxlines(std::span<const std::uint8_t> stream,
                                                      std::uint64_t streamline_count, std::uint64_t voxline_count,
                                                      const StreamContext& context);
// The VXLN table, one field per stream (so that the two streams decode side by side): voxels (of the
// table `coords`, as decoded by decode_voxel_coords) into `voxlines[j].voxel`, and own counts in
// [1, 2^31) with the synthetic flag into `voxlines[j].count_flags`.
void decode_voxline_voxels(std::span<const std::uint8_t> stream, std::span<const std::array<std::int32_t, 3>> coords,
                           std::span<VoxlineEntry> voxlines, const StreamContext& context);
void decode_voxline_counts(std::span<const std::uint8_t> stream, std::span<VoxlineEntry> voxlines,
                           const StreamContext& context);
// Groups: members < streamline_count and strictly increasing, names without NUL.
std::vector<StreamlineGroup> decode_group_stream(std::span<const std::uint8_t> stream, std::uint64_t streamline_count,
                                                 const StreamContext& context);

}  // namespace vxl
