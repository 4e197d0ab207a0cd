#include "converter/pipeline/conversion_plan.h"

#include <algorithm>
#include <array>
#include <string>

#include "converter/convert/segment_orders.h"
#include "format/base/direct_region_writer.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_levels.h"
#include "format/vxl_stream_writer.h"

namespace vxl {
namespace {

constexpr std::uint64_t kMiB = 1ull << 20;
// The program itself before any work: code, libraries, thread stacks, allocator slack (voxlines
// measures about 7 MiB of resident memory at start; the rest is margin).
constexpr std::uint64_t kBaselineBytes = 16 * kMiB;
// The voxel table while it is built and used, at its peak (build_table): hash index (coordinates and
// slots, with their growth: up to 40 bytes), counts per voxel (with growth: 32), tight bounds (with
// growth: 48), sort order, global id, the table itself (64) and cursor (8) — 200 bytes, and a margin.
constexpr std::uint64_t kPlanBytesPerVoxel = 240;
// With direct writes VERT is not held in memory when its blocks are few enough: each (voxel, level)
// block is written through a staging of its own of this size (less where an eighth of the memory left
// does not allow, but never under the minimum), then read back a chunk of voxels at a time for their
// orders. Why: VERT is the conversion's largest buffer (2.3 GB for 10M streamlines), and on a virtual
// machine whose host takes back the guest's free memory every fresh page costs about as much as
// writing and reading it back past the page cache (measured: 2.7 s per GiB faulted in, against 2.9 GB/s
// direct writes and 1.4-3 GB/s direct reads).
constexpr std::uint64_t kBlockStagingBytes = 128 * 1024;
constexpr std::uint64_t kMinBlockStagingBytes = 16 * 1024;
// The orders are built a run of voxels at a time (a chunk, handed out largest voxel first), in a buffer
// that holds kChunkVoxelsPerThread of the largest voxels per thread of the conversion (a range under a tight
// limit may order on fewer: its chunk is then larger than it needs): enough that no thread waits
// long for the one still ordering a large voxel at the chunk's end, and no more (each chunk's buffer is
// held twice). Measured on 2 cores: 1M streamlines (largest voxel's orders 5.6 MiB) took as long with
// 16 MiB chunks as with 78 MiB, and 120 MiB less memory; 10M (63 MiB) took 12.2 s in chunks of one
// voxel against 10.4 s in chunks of four. At least kMinOrderChunkBytes (each chunk one large direct write), at most
// kMaxOrderChunkBytes and an eighth of the memory left (never less than the largest voxel's orders).
constexpr std::uint64_t kChunkVoxelsPerThread = 2;
constexpr std::uint64_t kMinOrderChunkBytes = 16 * kMiB;
constexpr std::uint64_t kMaxOrderChunkBytes = 256 * kMiB;

bool is_packed(const ConversionCounts& c) { return c.positions == PositionEncoding::Packed; }

// Memory per ordering thread besides its sort buffers: a float32 block's end bits.
std::uint64_t end_bits_bytes(const ConversionCounts& c, std::uint32_t max_vertices) {
  return is_packed(c) ? 0 : (max_vertices / 64 + 1) * 8;
}

// The most VERT bytes of any run of consecutive voxels whose orders fit in a chunk (read back at once).
std::uint64_t largest_chunk_vertex_bytes(std::span<const VoxelEntry> voxels, std::uint64_t order_bytes,
                                         PositionEncoding positions, std::uint64_t order_chunk_bytes) {
  std::uint64_t most = 0;
  std::size_t end = 0;  // the end of the longest chunk from `first`: never decreases as `first` grows
  for (std::size_t first = 0; first < voxels.size(); ++first) {
    end = std::max(end, first + 1);
    while (end < voxels.size() &&
           orders_start(voxels, order_bytes, end + 1) - orders_start(voxels, order_bytes, first) <= order_chunk_bytes)
      ++end;
    const VoxelEntry& last = voxels[end - 1];
    most = std::max(most, last.vertex_first + last.vertex_count - voxels[first].vertex_first);
  }
  return most * vertex_bytes(positions);
}

// The parts of two batches being placed, from what pass 2 counted per point: 24 bytes per voxline (its staged
// entry, 12, and in the first range its table entry, 8), 8 per streamline (in the first range its voxline
// count and span take 12: the voxlines' share covers the rest) and a staged vertex per vertex, twice for the
// vectors' growth. A batch that needs more (a long streamline is held whole) takes the rest when it comes.
std::uint64_t staged_batches_bytes(const ConversionCounts& c) {
  const MetaSection& meta = c.meta;
  const double points = double(std::max<std::uint64_t>(1, meta.point_count));
  const double vertices = double(meta.point_count + meta.synthetic_point_count + meta.voxline_count);
  const double per_point = (24.0 * double(meta.voxline_count) + 8.0 * double(meta.streamline_count) +
                            double(vertex_bytes(c.positions)) * vertices) /
                           points;
  // A batch holds no more than the whole source.
  const std::uint64_t batch = std::min(c.batch_points, meta.point_count + meta.streamline_count);
  return static_cast<std::uint64_t>(2 * 2 * per_point * double(batch));
}

// How VERT's vertices are held: block by block (setting block_staging_bytes and the pool) when the blocks'
// staging takes at most an eighth of what is left and the pool at most half, and VERT is not held whole in
// memory (vertices_held_whole).
void plan_block_staging(const MemoryBudget& budget, const ConversionCounts& counts, ConversionPlan& plan) {
  const OrdersPool pool = orders_pool(counts.voxels, counts.order_bytes, counts.positions, plan.order_chunk_bytes);
  plan.pool_chunk_bytes = pool.chunk_bytes;
  plan.pool_read_back_bytes = pool.read_back_bytes;
  const std::uint64_t orders_part = pool.total();
  for (std::uint64_t staging = kBlockStagingBytes; staging >= kMinBlockStagingBytes && plan.block_staging_bytes == 0;
       staging /= 2) {
    const std::uint64_t total = block_staging_total(counts, staging);
    if (total <= budget.left() / 8 && std::max(total, orders_part) <= budget.left() / 2)
      plan.block_staging_bytes = staging;
  }
  if (plan.block_staging_bytes > 0)
    plan.pool_bytes = std::max(block_staging_total(counts, plan.block_staging_bytes), orders_part);
}

// Consecutive voxels, as many per range as fit in what the limit leaves: each range's vertices (packed:
// 4 bytes each, the end bit inside; float32: 12 bytes and an end bit; written block by block: only the
// float32 end bits) and its ordering threads' buffers.
// The orders are not held per range: they are built and written a chunk of voxels at a time (the chunk
// buffer is taken before this). An ordering thread's buffers grow with the largest voxel, so a range
// orders with fewer threads when they would take more than a quarter of the room (the orders do not
// depend on the thread count).
// Range r's ordering threads and what building it holds, in `room`.
struct RangeCost {
  const ConversionCounts& c;
  std::uint64_t room;
  bool block_staging;
  std::uint64_t per_thread(const VoxelRange& r) const {
    return order_scratch_bytes(r.max_vertices) + end_bits_bytes(c, r.max_vertices);
  }
  unsigned order_threads(const VoxelRange& r) const {
    return static_cast<unsigned>(std::clamp<std::uint64_t>(room / 4 / per_thread(r), 1, c.threads));
  }
  std::uint64_t operator()(const VoxelRange& r) const {
    const std::uint64_t v = r.vertex_end - r.vertex_first;
    const std::uint64_t end_bits = is_packed(c) ? 0 : (v / 64 + 1) * 8;
    const std::uint64_t held = block_staging ? end_bits : vertex_bytes(c.positions) * v + end_bits;
    return held + order_threads(r) * per_thread(r);
  }
};

// Whether VERT is held whole, in one range, beside the orders' two chunks: then it is, rather than written block by
// block and read back, which costs more than holding it (1M streamlines, 57M vertices, limit 512 MiB: 1.0-1.3 s of
// the placing pass).
bool vertices_held_whole(const MemoryBudget& budget, const ConversionCounts& c, std::uint64_t order_chunk_bytes) {
  const std::uint64_t chunks = 2 * chunk_buffer_bytes(order_chunk_bytes);
  if (c.range_request > 0 || c.vertex_blocks_request || chunks > budget.left()) return false;
  return RangeCost{c, budget.left() - chunks, false}(whole_range(c.voxels)) <= budget.left() - chunks;
}

std::vector<VoxelRange> cut_ranges(MemoryBudget& budget, const ConversionCounts& c, bool block_staging) {
  const std::uint64_t room = c.range_request > 0 ? std::min(c.range_request, budget.left()) : budget.left();
  const RangeCost cost{c, room, block_staging};
  auto order_threads = [&](const VoxelRange& r) { return cost.order_threads(r); };
  auto alone = [&](std::size_t i) {
    const VoxelEntry& v = c.voxels[i];
    VoxelRange r{i, i + 1, v.vertex_first, v.vertex_first + v.vertex_count, v.vertex_count};
    if (cost(r) > budget.left()) {  // refused
      budget.take(cost(r),
                  "voxel (" + std::to_string(v.coord[0]) + ", " + std::to_string(v.coord[1]) + ", " +
                      std::to_string(v.coord[2]) + ") of " + std::to_string(v.vertex_count) +
                      " vertices, with its sort buffers,",
                  ", or a smaller --voxel-size");
    }
    return r;
  };
  std::vector<VoxelRange> ranges;
  VoxelRange r;  // empty: the last one when there are no voxels (its pass still writes the tables)
  for (std::size_t i = 0; i < c.voxels.size(); ++i) {
    if (r.first == r.end) {
      r = alone(i);
      continue;
    }
    VoxelRange grown = r;
    grown.end = i + 1;
    grown.vertex_end = c.voxels[i].vertex_first + c.voxels[i].vertex_count;
    grown.max_vertices = std::max(grown.max_vertices, c.voxels[i].vertex_count);
    if (cost(grown) <= room) {
      r = grown;
    } else {
      ranges.push_back(r);
      r = alone(i);
    }
  }
  ranges.push_back(r);
  for (VoxelRange& each : ranges) {
    each.order_threads = order_threads(each);
    each.bytes = cost(each);
  }
  return ranges;
}

}  // namespace

std::uint64_t voxel_table_bytes_per_voxel(std::uint32_t levels) {
  // Each level of detail past the first adds counts per depth (32 with growth), a cursor (8), a LODS entry
  // (8) and the counts summed per voxel while the table is built (16).
  return kPlanBytesPerVoxel + 64 * (levels - 1);
}

ReadPlan plan_reading(MemoryBudget& budget) {
  const std::uint64_t limit = budget.limit();
  ReadPlan plan;
  budget.take(kBaselineBytes, "the program itself");
  plan.read_buffer_bytes = std::clamp<std::uint64_t>(limit / 64, 64 << 10, 4 * kMiB);
  budget.take(plan.read_buffer_bytes, "the read buffer");
  plan.batch_points = std::clamp<std::uint64_t>(limit / 64 / 16, 1024, 1 << 20);
  plan.max_header_bytes = std::max<std::uint64_t>(1, budget.left() / 4);
  plan.max_points_held = budget.left() / kHeldBytesPerPoint;
  return plan;
}

std::uint64_t block_staging_total(const ConversionCounts& c, std::uint64_t staging) {
  const std::uint32_t levels = c.level_count;
  const std::uint64_t bytes = vertex_bytes(c.positions);
  std::uint64_t total = kSpareBlockStagings * staging;  // the write queue's spares
  for (std::size_t g = 0; g < c.voxels.size(); ++g) {
    const std::span<const LevelEntry> row = level_row(c.levels, g, levels);
    for (std::uint32_t d = 0; d < levels; ++d) {  // as the placing pass cuts them
      const std::uint64_t first = depth_first_vertex(row, d), end = depth_end_vertex(c.voxels[g], row, d);
      if (end > first) total += DirectRegionWriter::staging_size((end - first) * bytes, staging);
    }
  }
  return total;
}

VoxelRange whole_range(std::span<const VoxelEntry> voxels) {
  VoxelRange r{0, voxels.size(), 0, 0, 0};
  if (voxels.empty()) return r;
  r.vertex_first = voxels.front().vertex_first;
  r.vertex_end = voxels.back().vertex_first + voxels.back().vertex_count;
  for (const VoxelEntry& v : voxels) r.max_vertices = std::max(r.max_vertices, v.vertex_count);
  return r;
}

std::uint64_t order_chunk_bytes(std::span<const VoxelEntry> voxels, std::uint64_t order_bytes, unsigned threads,
                                std::uint64_t request, std::uint64_t most) {
  std::uint64_t largest = 0;
  for (std::size_t i = 0; i < voxels.size(); ++i)
    largest = std::max(largest, orders_start(voxels, order_bytes, i + 1) - orders_start(voxels, order_bytes, i));
  const std::uint64_t wanted =
      std::clamp(kChunkVoxelsPerThread * threads * largest, kMinOrderChunkBytes, kMaxOrderChunkBytes);
  return std::max(largest, std::min({request > 0 ? request : wanted, order_bytes, most}));
}

std::uint64_t chunk_buffer_bytes(std::uint64_t order_chunk_bytes) {
  constexpr std::uint64_t block = DirectRegionWriter::kBlock;
  return (order_chunk_bytes + block - 1) / block * block + block;
}

OrdersPool orders_pool(std::span<const VoxelEntry> voxels, std::uint64_t order_bytes, PositionEncoding positions,
                       std::uint64_t order_chunk_bytes) {
  return {chunk_buffer_bytes(order_chunk_bytes), VxlStreamWriter::read_back_bytes(largest_chunk_vertex_bytes(
                                                     voxels, order_bytes, positions, order_chunk_bytes))};
}

namespace {

// What the limit leaves beside `plan`'s largest range.
std::uint64_t left_beside_ranges(const MemoryBudget& budget, const ConversionPlan& plan) {
  std::uint64_t largest = 0;
  for (const VoxelRange& r : plan.ranges) largest = std::max(largest, r.bytes);
  return budget.left() > largest ? budget.left() - largest : 0;
}

}  // namespace

bool plan_voxel_runs(MemoryBudget& budget, const ConversionPlan& plan, std::uint64_t runs_bytes) {
  if (runs_bytes > left_beside_ranges(budget, plan)) return false;
  budget.take(runs_bytes, "the voxel runs");
  return true;
}

bool plan_voxel_index_lists(MemoryBudget& budget, const ConversionPlan& plan, std::uint64_t lists_bytes) {
  if (plan.voxel_index_buffer_bytes == 0 || lists_bytes > left_beside_ranges(budget, plan) / 2) return false;
  budget.take(lists_bytes, "the voxel index's lists");
  return true;
}

std::uint64_t plan_voxel_index(const MemoryBudget& budget, std::uint64_t room, const ConversionCounts& counts) {
  if (voxel_index_bytes(counts.meta) == 0) return 0;  // no voxel index: too many streamlines for its entries
  const std::uint64_t lists = counts.meta.voxline_count * sizeof(IndexedVoxline);
  const std::uint64_t starts = 8 * (counts.voxels.size() + 1);
  // The tables' parts being read: VXLN (8 bytes an entry) and STRM (8), up to kVoxelIndexPartEntries each.
  const std::uint64_t parts = 8 * std::min(kVoxelIndexPartEntries, counts.meta.voxline_count) +
                              8 * std::min(kVoxelIndexPartEntries, counts.meta.streamline_count + 1);
  std::uint64_t largest = 0;  // the largest voxel's list, at most: a voxline has at least one vertex
  std::size_t largest_at = 0;
  for (std::size_t i = 0; i < counts.voxels.size(); ++i)
    if (counts.voxels[i].vertex_count > largest) largest = counts.voxels[i].vertex_count, largest_at = i;
  largest = std::min(lists, largest * sizeof(IndexedVoxline));
  if (largest + starts > room) {
    const VoxelEntry& v = counts.voxels[largest_at];
    budget.fail(largest + starts, budget.limit() - std::min(budget.limit(), room),
                "the voxel index's list of voxel (" + std::to_string(v.coord[0]) + ", " + std::to_string(v.coord[1]) +
                    ", " + std::to_string(v.coord[2]) + ")",
                ", or a smaller --voxel-size");
  }
  // The largest list goes first: where the room holds it but not also the tables' parts being read (at most
  // 16 MB), those go past the limit, rather than refusing a limit that fits every range.
  const std::uint64_t free = room - starts;
  return std::max(largest, std::min(lists, free > parts ? free - parts : 0));
}

ConversionPlan plan_conversion(MemoryBudget& budget, const ConversionCounts& counts) {
  ConversionPlan plan;
  plan.table_buffer_entries = std::clamp<std::uint64_t>(budget.limit() >> 14, 1 << 15, 1 << 18);
  budget.take(2 * plan.table_buffer_entries * (sizeof(VoxlineEntry) + sizeof(std::uint64_t)),
              "the buffers of the voxline and streamline tables");
  budget.take(counts.meta.streamline_count * sizeof(std::array<std::uint32_t, 2>),
              "the voxel span of every streamline");
  plan.staged_bytes = staged_batches_bytes(counts);
  budget.take(plan.staged_bytes, "the voxlines of two batches being placed");
  // Direct writes (the output bypasses the page cache) where the limit leaves room for their staging.
  if (budget.limit() >= kDirectWritesFromLimit) {
    plan.direct_staging_bytes = kSectionDirectStagingBytes;
    budget.take(VxlStreamWriter::kCount * kSectionDirectStagingBytes, "the staging of the output's direct writes");
  }
  plan.order_chunk_bytes = order_chunk_bytes(counts.voxels, counts.order_bytes, counts.threads,
                                             counts.order_chunk_request, budget.left() / 8);
  // What the pool, the orders' chunks and the ranges take is given back before the write stage.
  const std::uint64_t room_at_write = budget.left();
  if (plan.direct_staging_bytes > 0 && !vertices_held_whole(budget, counts, plan.order_chunk_bytes))
    plan_block_staging(budget, counts, plan);
  if (plan.block_staging_bytes > 0)
    budget.take(plan.pool_bytes, "the vertex blocks being written, then the orders being built and their vertices");
  else
    budget.take(chunk_buffer_bytes(plan.order_chunk_bytes) * (plan.direct_staging_bytes > 0 ? 2 : 1),
                "the part of the orders being written", ", or a smaller --voxel-size");
  plan.ranges = cut_ranges(budget, counts, plan.block_staging_bytes > 0);
  plan.voxel_index_buffer_bytes = plan_voxel_index(budget, room_at_write, counts);
  return plan;
}

}  // namespace vxl
