// Per-voxel segment orders (paper §"View-Dependent Line Order per Axis"; spec §5.5, §6.4).
//
// For each stored direction d, a voxel's segments (a, b) are sorted by dot(a + b, d) ascending, ties by
// block-local index, so the file is deterministic. Only one of d / −d is stored: the renderer reads the
// order backwards for −d.
#pragma once

#include <array>
#include <memory>
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

// Writes one voxel's orders at a time, for callers that do other per-voxel work in the same pass (the
// unpacker computes the voxel's tight bounds while its vertices are in cache). It keeps its sort
// buffers between voxels: use one per thread.
class VoxelOrderWriter {
 public:
  explicit VoxelOrderWriter(const OrderSetSpec& set);
  ~VoxelOrderWriter();
  VoxelOrderWriter(VoxelOrderWriter&&) noexcept;

  // Sorts voxel `v`'s segments (the vertices of its block that do not end a voxline in `ends`) for every
  // direction of the set and writes its K orders at `dst` (the ORDR payload plus v.order_offset; the
  // voxel's flags and order_offset as layout_orders set them). Padding bytes are left as they are.
  void write(const VoxelEntry& v, std::span<const float> vertices, const VoxlineEnds& ends, std::uint8_t* dst);

 private:
  struct Scratch;
  std::vector<std::array<float, 3>> directions_;
  std::vector<int> axis_of_;  // the component of an axis direction, -1 for any other
  std::unique_ptr<Scratch> scratch_;
};

// Sorts every voxel's segments for every direction of `set` into `orders`, the ORDR payload laid out
// by layout_orders (padding bytes are left as they are: zero in a fresh payload).
void build_orders_into(std::span<const VoxelEntry> voxels, std::span<const float> vertices, const VoxlineEnds& ends,
                       const OrderSetSpec& set, std::span<std::uint8_t> orders, unsigned threads, const ProgressFn& progress);

struct BuiltOrders {
  std::vector<DirectionEntry> directions;
  std::vector<std::uint8_t> bytes;  // the ORDR payload
};

// All of the above in memory: sets the voxels' flags and order_offset and the meta's order fields.
BuiltOrders build_orders(VoxelizedTractogram& voxelized, const OrderSetSpec& set, unsigned threads,
                         const ProgressFn& progress);

}  // namespace vxl
