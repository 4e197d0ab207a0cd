// Per-voxel segment orders (paper §"View-Dependent Line Order per Axis"; spec §5.5, §6.4).
//
// For each stored direction d, a voxel's segments (a, b) are sorted by dot(a + b, d) ascending, ties by
// block-local index, so the file is deterministic. Only one of d / −d is stored: the renderer reads the
// order backwards for −d.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "voxelize.h"
#include "vxl_layout.h"

namespace vxl {

struct OrderSetSpec {
  OrderSet kind = OrderSet::Axis;
  std::string name = "axis";
  std::vector<std::array<float, 3>> directions;  // stored directions (unit vectors)
};

// "axis" (K = 3: ±X, ±Y, ±Z) or "axis+diag" (K = 7: also the 8 cube diagonals).
// Throws vxl::Error (Usage) for anything else.
OrderSetSpec parse_order_set(const std::string& name);

// The DIRS entries of an order set.
std::vector<DirectionEntry> order_directions(const OrderSetSpec& set);

// Sets every voxel's flags (order entry width) and order_offset for K = `stored_orders`; returns the
// size of the ORDR payload, so that it can be allocated before the orders are built.
std::uint64_t layout_orders(std::span<VoxelEntry> voxels, std::uint32_t stored_orders);

// Sorts every voxel's segments for every direction of `set` into `orders`, the ORDR payload laid out
// by layout_orders (padding bytes are left as they are: zero in a fresh payload).
void build_orders_into(std::span<const VoxelEntry> voxels, std::span<const float> vertices, const VoxlineEnds& ends,
                       const OrderSetSpec& set, std::span<std::uint8_t> orders, unsigned threads, const ProgressFn& progress);

// An upper bound of what build_orders_into allocates per worker thread (its sort buffers, growth
// included) when no voxel has more than `max_vertices` vertices, for callers that budget memory.
std::uint64_t order_scratch_bytes(std::uint32_t max_vertices);

struct BuiltOrders {
  std::vector<DirectionEntry> directions;
  std::vector<std::uint8_t> bytes;  // the ORDR payload
};

// All of the above in memory: sets the voxels' flags and order_offset and the meta's order fields.
BuiltOrders build_orders(VoxelizedTractogram& voxelized, const OrderSetSpec& set, unsigned threads,
                         const ProgressFn& progress);

}  // namespace vxl
