// How a conversion within a memory limit (streaming_convert.h) is split, worked out from the limit and the
// counts of the passes before: how large a batch of streamlines is read at a time, how the output is
// written (through the page cache, past it, or VERT block by block and read back), how large a chunk of
// orders is built at a time and which ranges of voxels are built in one pass each. Pure arithmetic on a
// MemoryBudget: no I/O, so that the split can be tested without a source or an output. A limit too small
// for a part is refused here (MemoryBudget::fail) before any of the work it sizes is done.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "converter/pipeline/memory_budget.h"
#include "format/vxl_layout.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"

namespace vxl {

// Spare stagings for the blocks' write queue (DirectWriteQueue): how far the writes may fall behind.
inline constexpr std::uint64_t kSpareBlockStagings = 32;
// Memory per point of a batch being read, at worst: two batches (one read while the other is processed),
// each of whose positions may have twice the capacity in use.
inline constexpr std::uint64_t kHeldBytesPerPoint = 2 * 2 * 3 * sizeof(float);
// The output is written past the page cache (DirectRegionWriter) under limits of at least this much.
inline constexpr std::uint64_t kDirectWritesFromLimit = 256ull << 20;
// The output's direct writes are staged this much per section.
inline constexpr std::uint64_t kSectionDirectStagingBytes = 2ull << 20;

// The voxel table's bytes per voxel while it is built, with `levels` levels of detail.
std::uint64_t voxel_table_bytes_per_voxel(std::uint32_t levels);

// Sizes the conversion otherwise derives from the limit, set by tests (to reach on small data what
// only large data would) and benchmarks; 0 keeps the derived value. The output does not depend on them.
struct StreamingTuning {
  std::uint64_t order_chunk_bytes = 0;  // orders built and written this much at a time (or one voxel)
  std::uint64_t range_bytes = 0;        // ranges of voxels cut to hold at most this much (or one voxel; 0: the limit)
  // VERT written block by block wherever the limit allows it (direct writes), also where it could be held whole.
  bool vertex_blocks = false;
};

// How the source is read, from the limit alone (before anything is read).
struct ReadPlan {
  std::uint64_t read_buffer_bytes = 0;
  // A batch holds whole streamlines, up to the first that brings its points and streamlines to this many.
  std::uint64_t batch_points = 0;
  std::uint64_t max_header_bytes = 0;  // the longest TCK header read
  std::uint64_t max_points_held = 0;   // points a batch may hold (a longer streamline is refused)
};
// Takes the program's own memory and the read buffer from `budget`.
ReadPlan plan_reading(MemoryBudget& budget);

// Consecutive voxels built in one pass over the source.
struct VoxelRange {
  std::size_t first = 0, end = 0;  // voxels
  std::uint64_t vertex_first = 0, vertex_end = 0;
  std::uint32_t max_vertices = 0;  // of its largest voxel
  unsigned order_threads = 1;      // threads building its orders (fewer where their buffers do not fit)
  std::uint64_t bytes = 0;         // what building it holds besides what plan_conversion took: vertices, sorts
};

// Every voxel (laid out: vertex_first and vertex_count set) as one range, ordered on one thread.
VoxelRange whole_range(std::span<const VoxelEntry> voxels);

// What the voxel table fixed, for plan_conversion.
struct ConversionCounts {
  const MetaSection& meta;             // streamline, point, synthetic point and voxline counts
  std::span<const VoxelEntry> voxels;  // laid out: vertex_first, vertex_count and order_offset set
  std::span<const LevelEntry> levels;  // LODS, voxel-major (empty with one level)
  std::uint32_t level_count = 1;
  PositionEncoding positions = PositionEncoding::Packed;
  std::uint64_t order_bytes = 0;          // ORDB's payload
  unsigned threads = 1;                   // resolved
  std::uint64_t batch_points = 0;         // ReadPlan::batch_points
  std::uint64_t order_chunk_request = 0;  // StreamingTuning::order_chunk_bytes (0: derived)
  std::uint64_t range_request = 0;        // StreamingTuning::range_bytes (0: what the limit leaves)
  bool vertex_blocks_request = false;     // StreamingTuning::vertex_blocks
};

struct ConversionPlan {
  // Voxline and streamline table entries written at once (TableAppender: two buffers of each, one filling while
  // the other is written): more under larger limits, so that a large source's tables take fewer writes.
  std::uint64_t table_buffer_entries = 0;
  std::uint64_t staged_bytes = 0;          // two batches' staged voxlines, as first taken (they may grow)
  std::uint64_t direct_staging_bytes = 0;  // per section; 0: the output is written through the page cache
  std::uint64_t order_chunk_bytes = 0;     // orders built and written at once (at least the largest voxel's)
  // > 0: VERT is written block by block through stagings of this size and read back for the orders.
  std::uint64_t block_staging_bytes = 0;
  // Written block by block: one buffer for the blocks' stagings while they are placed, then two orders
  // chunks (pool_chunk_bytes each) and two chunks' vertices read back (pool_read_back_bytes each).
  std::uint64_t pool_bytes = 0, pool_chunk_bytes = 0, pool_read_back_bytes = 0;
  std::vector<VoxelRange> ranges;  // at least one (with no voxels: one empty range, which writes the tables)
  // The write stage's voxel index (VxlStreamWriter::append_voxel_index), where its lists are not filled while
  // placing (plan_voxel_index_lists): the lists sorted at once, one pass over VXLN and STRM per buffer full
  // (plan_voxel_index). 0: the file has no voxel index.
  std::uint64_t voxel_index_buffer_bytes = 0;
};

// Takes from `budget`, in this order: the tables' buffers, every streamline's voxel span, two batches'
// staged voxlines, the direct writes' staging, the pool or the orders chunks, and each range's vertices
// and sort buffers (the largest range's: ranges are cut to fit in what is left). The voxel index's buffer
// comes after the ranges, in the memory they give back: plan_voxel_index, from what is left before the
// pool and the ranges are taken.
ConversionPlan plan_conversion(MemoryBudget& budget, const ConversionCounts& counts);

// Whether the voxel runs the counting pass recorded (`runs_bytes`: every streamline's voxlines, so that the
// placing passes need not voxelise again) are kept: when they fit beside what `plan` took from `budget` and
// its largest range. Then they are taken from `budget`.
bool plan_voxel_runs(MemoryBudget& budget, const ConversionPlan& plan, std::uint64_t runs_bytes);

// Whether the voxel index's lists are filled as the first range is placed (VoxelIndexLists, of `lists_bytes`)
// rather than sorted at the write stage from the tables read back: when the file has a voxel index and the
// lists take at most half of what the limit leaves beside `plan` and its largest range (the rest is margin for
// batches that grow). Then they are taken from `budget`.
bool plan_voxel_index_lists(MemoryBudget& budget, const ConversionPlan& plan, std::uint64_t lists_bytes);

// The voxel index's buffer at the write stage, when `room` is what the limit leaves then (the ranges, the
// pool and the orders' chunks given back): every voxel's list at once (4 bytes a voxline) when they fit,
// else as many as fit beside the list starts (8 bytes a voxel) and the tables' parts being read
// (kVoxelIndexPartEntries of each), but never fewer than the largest voxel's list, whose length is at most
// its vertex count. Throws Unsupported (MemoryBudget::fail) when `room` does not hold that list and the
// starts. 0 when the file has no voxel index (more streamlines than its entries number).
std::uint64_t plan_voxel_index(const MemoryBudget& budget, std::uint64_t room, const ConversionCounts& counts);

// Where voxel i's orders start in ORDB (i = voxel count: the payload's end).
inline std::uint64_t orders_start(std::span<const VoxelEntry> voxels, std::uint64_t order_bytes, std::size_t i) {
  return i < voxels.size() ? voxels[i].order_offset : order_bytes;
}

// The memory VERT's stagings take when written block by block with stagings of `staging` bytes: the write
// queue's spares and each (voxel, level) block's own (DirectRegionWriter::staging_size).
std::uint64_t block_staging_total(const ConversionCounts& counts, std::uint64_t staging);

// The orders' chunk (ConversionPlan::order_chunk_bytes): `request` where it is > 0, else two of the largest voxels'
// orders per ordering thread within 16 MiB and 256 MiB; at most `most` and the whole payload, and never less than
// the largest voxel's orders.
std::uint64_t order_chunk_bytes(std::span<const VoxelEntry> voxels, std::uint64_t order_bytes, unsigned threads,
                                std::uint64_t request, std::uint64_t most);

// The buffer one chunk of orders of up to `order_chunk_bytes` is built in: block-aligned and a block larger, for
// the orders start where their first byte falls in its block of the file (VxlStreamWriter::append_from_block).
std::uint64_t chunk_buffer_bytes(std::uint64_t order_chunk_bytes);

// Where VERT is read back for its orders (RangeOrderSettings::pool): two chunks' orders being built and written, of
// chunk_bytes each, then two chunks' vertices being read, of read_back_bytes each (the largest chunk's, its blocks
// around it).
struct OrdersPool {
  std::uint64_t chunk_bytes = 0, read_back_bytes = 0;
  std::uint64_t total() const { return 2 * (chunk_bytes + read_back_bytes); }
};
OrdersPool orders_pool(std::span<const VoxelEntry> voxels, std::uint64_t order_bytes, PositionEncoding positions,
                       std::uint64_t order_chunk_bytes);

}  // namespace vxl
