// The orders stage (range_orders.h): a chunk of voxels at a time, from the range's vertices in memory or read back.
#include "converter/pipeline/range_orders.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <vector>

#include "format/base/batch_queue.h"
#include "format/base/direct_region_writer.h"

namespace vxl {
namespace {

using Clock = std::chrono::steady_clock;

// One chunk of voxels on its way through the orders' queue: its vertices, its voxels largest first, the buffer its
// orders are built in and the next voxel to hand out.
struct OrderChunk {
  std::size_t first = 0, end = 0;  // voxels
  std::span<const std::uint8_t> vertices;
  std::vector<std::size_t> by_size;
  std::span<std::uint8_t> orders;  // where the chunk's orders start in `block`
  std::uint8_t* block = nullptr;   // the block-aligned buffer they are built in
  std::atomic<std::size_t> next{0};
};

// Voxel g's orders at `dst`, from its block in `vertices` (the part of VERT from vertex `vertices_first`): the orders
// sort the positions the file holds. A float32 block's voxline ends are copied into `block_ends` (a packed block holds
// its own).
void write_voxel_orders(const OrderedTable& table, const RangeOrderSettings& settings, const VoxelRange& r,
                        std::size_t g, std::span<const std::uint8_t> vertices, std::uint64_t vertices_first,
                        VoxelOrderWriter& writer, VoxlineEnds& block_ends, std::uint8_t* dst) {
  VoxelEntry v = table.voxels[g];
  const std::span<const LevelEntry> row = level_row(table.levels, g, table.level_count);
  const std::uint64_t at = v.vertex_first - vertices_first;
  v.vertex_first = 0;
  if (settings.positions == PositionEncoding::Float32) {
    block_ends.reset(v.vertex_count);
    const std::uint64_t in_range = table.voxels[g].vertex_first - r.vertex_first;  // float_ends counts from the range
    for (std::uint32_t e = 0; e < v.vertex_count; ++e)
      if (settings.float_ends->test(in_range + e)) block_ends.set(e);
    const float* xyz = reinterpret_cast<const float*>(vertices.data()) + 3 * at;
    writer.write(v, row, {xyz, 3 * std::size_t(v.vertex_count)}, block_ends, dst);
    return;
  }
  writer.write_packed(v, row, reinterpret_cast<const std::uint32_t*>(vertices.data()) + at, dst);
}

}  // namespace

// A chunk of consecutive voxels at a time, as a queue (run_batch_queue): while the chunk's voxels are ordered on the
// range's ordering threads (largest first), the next chunk's vertices are read and, with direct writes, the chunk
// before is written.
double write_range_orders(VxlStreamWriter& out, const OrderedTable& table, const VoxelRange& r,
                          std::span<const std::uint8_t> range_vertices, const RangeOrderSettings& settings) {
  if (settings.positions == PositionEncoding::Float32 && settings.float_ends == nullptr)
    throw std::logic_error("write_range_orders: float32 positions need their voxline ends");
  const auto orders_start = [&](std::size_t i) { return vxl::orders_start(table.voxels, table.order_bytes, i); };
  std::vector<std::size_t> cuts{r.first};  // chunk c: voxels [cuts[c], cuts[c + 1])
  while (cuts.back() < r.end) {
    const std::size_t first = cuts.back();
    std::size_t end = first + 1;
    while (end < r.end && orders_start(end + 1) - orders_start(first) <= settings.order_chunk_bytes) ++end;
    cuts.push_back(end);
  }
  auto vertex_start = [&](std::size_t i) { return i < r.end ? table.voxels[i].vertex_first : r.vertex_end; };
  const std::uint64_t vertex_size = vertex_bytes(settings.positions);
  const bool read_back = settings.pool != nullptr, direct = settings.direct;
  // The chunks' orders and the vertices read back: in the pool after the blocks' staging is done with. A chunk's
  // buffer is block-aligned and one block larger than its orders: they start where their first byte falls in its
  // block of the file, so that the writer writes their whole blocks from the buffer without a copy
  // (VxlStreamWriter::append_from_block). Through the page cache a chunk is written before the next is built: one
  // buffer. The buffers are taken once (chunk_buffer_bytes, for the largest chunk) and not cleared: the writers
  // write every byte of their voxels' orders, padding included. (Regrowing and zeroing them per chunk took 3 of
  // the 11 s of a 10M conversion's orders: fresh pages cost much on a virtual machine.)
  std::unique_ptr<std::uint8_t, void (*)(void*)> own_blocks[2] = {{nullptr, std::free}, {nullptr, std::free}};
  std::uint8_t* blocks[2] = {};
  std::array<std::span<std::uint8_t>, 2> read_buffers;
  if (read_back)
    for (int b = 0; b < 2; ++b) {
      blocks[b] = settings.pool + b * settings.pool_chunk_bytes;
      read_buffers[b] = {settings.pool + 2 * settings.pool_chunk_bytes + b * settings.pool_read_back_bytes,
                         static_cast<std::size_t>(settings.pool_read_back_bytes)};
    }
  // Per ordering thread, sized for the range's largest voxel once (fresh pages are dear; see above), by the queue's
  // thread (reads and writes take a thread each beside the ordering threads: they wait on the disk).
  const unsigned threads = r.order_threads + (read_back ? 1 : 0) + (direct ? 1 : 0);
  std::vector<std::optional<VoxelOrderWriter>> writers(threads);
  std::vector<VoxlineEnds> block_ends(threads);
  OrderChunk chunks[2];
  std::size_t next_chunk = 0;
  const auto read = [&](int slot) {
    if (next_chunk + 1 >= cuts.size()) return false;
    OrderChunk& k = chunks[slot];
    k.first = cuts[next_chunk];
    k.end = cuts[next_chunk + 1];
    ++next_chunk;
    const std::uint64_t from = vertex_start(k.first), to = vertex_start(k.end);
    k.vertices = read_back ? out.read_back(VxlStreamWriter::kVert, (to - from) * vertex_size, read_buffers[slot])
                           : range_vertices.subspan((from - r.vertex_first) * vertex_size, (to - from) * vertex_size);
    return true;
  };
  double seconds = 0;
  auto t0 = Clock::now();
  const auto prepare = [&](int slot) {
    t0 = Clock::now();
    OrderChunk& k = chunks[slot];
    const int b = direct ? slot : 0;
    if (blocks[b] == nullptr) {
      void* p = std::aligned_alloc(DirectRegionWriter::kBlock, chunk_buffer_bytes(settings.order_chunk_bytes));
      if (p == nullptr) throw std::bad_alloc();
      own_blocks[b].reset(static_cast<std::uint8_t*>(p));
      blocks[b] = own_blocks[b].get();
    }
    const std::uint64_t base = orders_start(k.first);
    k.block = blocks[b];
    k.orders = {k.block + out.block_lead(VxlStreamWriter::kOrdb, base),
                static_cast<std::size_t>(orders_start(k.end) - base)};
    k.by_size.resize(k.end - k.first);
    std::iota(k.by_size.begin(), k.by_size.end(), k.first);
    std::stable_sort(k.by_size.begin(), k.by_size.end(), [&](std::size_t a, std::size_t b) {
      return table.voxels[a].vertex_count > table.voxels[b].vertex_count;
    });
    k.next = 0;
  };
  const auto order = [&](int slot, std::uint64_t, unsigned t) {  // voxels handed out one at a time
    OrderChunk& k = chunks[slot];
    const std::uint64_t base = orders_start(k.first);
    for (std::size_t i = k.next++; i < k.by_size.size(); i = k.next++) {
      if (!writers[t]) writers[t].emplace(*settings.order_set, r.max_vertices);
      const std::size_t g = k.by_size[i];
      write_voxel_orders(table, settings, r, g, k.vertices, vertex_start(k.first), *writers[t], block_ends[t],
                         k.orders.data() + (table.voxels[g].order_offset - base));
    }
  };
  const auto write = [&](int slot) {
    out.append_from_block(VxlStreamWriter::kOrdb, chunks[slot].block, chunks[slot].orders.size());
  };
  const auto finish = [&](int slot) {
    if (!direct) write(slot);
    seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    if (settings.progress)
      settings.progress(double(chunks[slot].end - r.first) / double(std::max<std::size_t>(1, r.end - r.first)));
  };
  run_batch_queue(
      threads, {r.order_threads, direct ? 1u : 0u, true, {}}, read, prepare, order,
      [&](int slot, std::uint64_t, unsigned) { write(slot); }, finish);
  if (cuts.size() == 1 && settings.progress) settings.progress(1.0);  // no voxels: nothing to order
  return seconds;
}

}  // namespace vxl
