// Levels of detail (spec §5.12, §6.5; since 2.1).
//
// Every streamline has a fixed pseudo-random depth; level d of a file holds the streamlines of depth >= d,
// about 1/8^d of them (level 0: all). Inside each voxel's block the voxlines of deeper streamlines come
// first, so that level d of a voxel is a prefix of its block, and each level stores its own orders. A
// renderer that draws level d of a voxel reads that prefix and those orders only: it costs in proportion
// to the level's segments, and the level keeps the within-voxel back-to-front order.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>

#include "format/vxl_layout.h"

namespace vxl {

inline constexpr std::uint32_t kMaxLevels = 8;
// Each level keeps 1/8 of the next finer one. Why 8, not 4: the coarse levels' orders then add 1/7 to the
// orders rather than 1/3 (on a dense 1M-streamline set, 1.24x rather than 1.34x the TCK's size).
inline constexpr std::uint32_t kLevelRatio = 8;
// Level 4 keeps about 1/4096 of the streamlines: a 10-million streamline file draws ~2 400 of them.
inline constexpr std::uint32_t kDefaultLevels = 5;

// One LODS entry: the prefix of a voxel's block that holds level d >= 1 (spec §5.12).
struct LevelEntry {
  std::uint32_t vertex_count;
  std::uint32_t segment_count;
};
static_assert(sizeof(LevelEntry) == 8);

// The deepest level that streamline `index` (its place in the source, from 0) belongs to, for a file of
// `level_count` levels (spec §6.5): a third of the trailing zero bits of a SplitMix64 hash of the index,
// at most level_count - 1. A streamline is in level d exactly when its depth is >= d, so levels nest, and
// each holds an eighth of the next finer one on average, spread over the whole source.
constexpr std::uint32_t streamline_depth(std::uint64_t index, std::uint32_t level_count) {
  std::uint64_t z = index + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  const auto depth = static_cast<std::uint32_t>(std::countr_zero(z) / 3);  // countr_zero(0) = 64
  return std::min(depth, level_count > 0 ? level_count - 1 : 0u);
}

// The vertices and segments of level `level` of a voxel: its VOXT counts for level 0, else its LODS
// entry `level - 1` (`row` holds the voxel's level_count - 1 entries).
inline LevelEntry voxel_level(const VoxelEntry& v, std::span<const LevelEntry> row, std::uint32_t level) {
  return level == 0 ? LevelEntry{v.vertex_count, v.segment_count} : row[level - 1];
}

// Where, inside a voxel's block, the voxlines of streamlines of depth `depth` lie: after those of the
// deeper ones (level depth + 1's prefix), up to the end of level depth's prefix (spec §5.4).
inline std::uint32_t depth_first_vertex(std::span<const LevelEntry> row, std::uint32_t depth) {
  return depth < row.size() ? row[depth].vertex_count : 0;
}
inline std::uint32_t depth_end_vertex(const VoxelEntry& v, std::span<const LevelEntry> row, std::uint32_t depth) {
  return voxel_level(v, row, depth).vertex_count;
}

// Bytes of one level's K orders, padded to 4 (spec §5.5): entries are as wide as the level's prefix needs.
constexpr std::uint64_t level_orders_size(const LevelEntry& level, std::uint32_t k, OrderPacking packing) {
  return voxel_orders_size(level.vertex_count, level.segment_count, k, packing);
}

// Where level `level`'s orders start, from the voxel's order_offset: after the finer levels' orders.
inline std::uint64_t level_orders_offset(const VoxelEntry& v, std::span<const LevelEntry> row, std::uint32_t level,
                                         std::uint32_t k, OrderPacking packing) {
  std::uint64_t offset = v.order_offset;
  for (std::uint32_t d = 0; d < level; ++d) offset += level_orders_size(voxel_level(v, row, d), k, packing);
  return offset;
}

// All of a voxel's orders, every level.
inline std::uint64_t voxel_all_orders_size(const VoxelEntry& v, std::span<const LevelEntry> row, std::uint32_t k,
                                           OrderPacking packing) {
  std::uint64_t bytes = level_orders_size(voxel_level(v, row, 0), k, packing);
  for (const LevelEntry& e : row) bytes += level_orders_size(e, k, packing);
  return bytes;
}

}  // namespace vxl
