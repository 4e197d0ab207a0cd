// The orders of a range of voxels (spec §5.5 ORDB), a chunk of voxels at a time, from the range's vertices in
// memory or read back from the output: the orders stage every .vxl this program writes goes through, a
// conversion's (one call per range of its plan) and an unpacked package's (one range of every voxel).
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "converter/convert/segment_orders.h"
#include "converter/convert/voxelize.h"
#include "converter/pipeline/conversion_plan.h"
#include "format/vxl_layout.h"
#include "format/vxl_positions.h"
#include "format/vxl_stream_writer.h"

namespace vxl {

// The output's voxel table, laid out (layout_orders: order_offset set), as the orders read it.
struct OrderedTable {
  std::span<const VoxelEntry> voxels;
  std::span<const LevelEntry> levels;  // LODS, voxel-major (empty with one level)
  std::uint32_t level_count = 1;
  std::uint64_t order_bytes = 0;  // ORDB's payload
};

// How a range's orders are built and where its vertices come from.
struct RangeOrderSettings {
  const OrderSetSpec* order_set = nullptr;
  PositionEncoding positions = PositionEncoding::Packed;
  std::uint64_t order_chunk_bytes = 0;  // ConversionPlan::order_chunk_bytes (at least the largest voxel's orders)
  bool direct = false;                  // the output is written past the page cache: a chunk is written beside
                                        // the next one's ordering, on a thread of its own
  // Float32 positions: the range's voxline ends, numbered from its first vertex (packed words hold their own).
  const VoxlineEnds* float_ends = nullptr;
  // VERT written block by block: the buffer its chunks are read back into and the orders built in (two orders
  // chunks of pool_chunk_bytes, then two vertex chunks of pool_read_back_bytes: ConversionPlan's pool). Null: the
  // range's vertices are in memory (write_range_orders' `range_vertices`).
  std::uint8_t* pool = nullptr;
  std::uint64_t pool_chunk_bytes = 0, pool_read_back_bytes = 0;
  std::function<void(double)> progress;  // the fraction of the range's voxels ordered; may be empty
};

// Appends range r's orders to ORDB (r.order_threads ordering, largest voxel of each chunk first; the orders do not
// depend on the thread count) from its vertices: `range_vertices` (VERT's bytes of the range), or read back from
// VERT into the pool. Returns the seconds spent building and writing the chunks.
double write_range_orders(VxlStreamWriter& out, const OrderedTable& table, const VoxelRange& r,
                          std::span<const std::uint8_t> range_vertices, const RangeOrderSettings& settings);

}  // namespace vxl
