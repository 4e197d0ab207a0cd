// Per-voxel segment orders (paper §"View-Dependent Line Order per Axis"; spec §5.5, §6.4).
//
// For each stored direction d, a voxel's segments (a, b) are sorted by dot(a + b, d) ascending, ties by
// block-local index, so the file is deterministic. Only one of d / −d is stored: the renderer reads the
// order backwards for −d.
#pragma once

#include <array>
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

struct BuiltOrders {
  std::vector<DirectionEntry> directions;
  std::vector<std::uint8_t> bytes;  // the ORDR payload
};

// Sorts every voxel's segments for every direction; sets each voxel's flags and order_offset.
BuiltOrders build_orders(VoxelizedTractogram& voxelized, const OrderSetSpec& set, unsigned threads,
                         const ProgressFn& progress);

}  // namespace vxl
