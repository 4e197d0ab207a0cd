// The streaming conversion's orders of a range, a chunk of voxels at a time, from the range's vertices
// in memory or read back (streaming_conversion.h).
#include "converter/pipeline/streaming_conversion.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <optional>

#include "converter/pipeline/chunk_vertices.h"
#include "format/base/parallel.h"

namespace vxl::streaming {

// The orders of range r's voxels, a chunk of consecutive voxels at a time (each chunk's voxels spread
// over the range's ordering threads), built in place in ORDB. The vertices are range r's part of VERT in
// memory (`range_vertices`), or, when VERT was written block by block, read back a chunk at a time: the
// next chunk's on another thread while this one is built.
void StreamingConversion::write_orders(const VoxelRange& r, std::span<const std::uint8_t> range_vertices,
                                       const std::string& stage) {
  // Per ordering thread, sized for the range's largest voxel once (fresh pages are dear; see above).
  std::vector<std::optional<VoxelOrderWriter>> writers(r.order_threads);
  std::vector<VoxlineEnds> block_ends(r.order_threads);
  std::vector<std::size_t> cuts{r.first};  // chunk c: voxels [cuts[c], cuts[c + 1])
  while (cuts.back() < r.end) {
    const std::size_t first = cuts.back();
    std::size_t end = first + 1;
    while (end < r.end && orders_start(end + 1) - orders_start(first) <= plan_.order_chunk_bytes) ++end;
    cuts.push_back(end);
  }
  auto vertex_start = [&](std::size_t i) { return i < r.end ? table_.voxels[i].vertex_first : r.vertex_end; };
  std::vector<std::uint64_t> chunk_bounds;
  for (std::size_t cut : cuts) chunk_bounds.push_back(vertex_start(cut));
  const std::uint64_t vertex_size = vertex_bytes(job_.settings.positions);
  // The chunks' orders and the vertices read back: in pool_ after the blocks' staging is done with. A chunk's
  // buffer is block-aligned and one block larger than its orders: they start where their first byte falls in its
  // block of the file, so that the writer writes their whole blocks from the buffer without a copy
  // (VxlStreamWriter::append_from_block).
  std::unique_ptr<std::uint8_t, void (*)(void*)> own_chunks[2] = {{nullptr, std::free}, {nullptr, std::free}};
  std::uint8_t* chunks[2] = {};
  std::optional<ChunkVertices> chunk_vertices;
  if (plan_.block_staging_bytes > 0) {
    std::array<std::span<std::uint8_t>, 2> read_buffers;
    for (int b = 0; b < 2; ++b) {
      chunks[b] = pool_.get() + b * plan_.pool_chunk_bytes;
      read_buffers[b] = {pool_.get() + 2 * plan_.pool_chunk_bytes + b * plan_.pool_read_back_bytes,
                         plan_.pool_read_back_bytes};
    }
    chunk_vertices.emplace(*out_, read_buffers, vertex_size, std::move(chunk_bounds));
  } else {
    chunk_vertices.emplace(range_vertices, r.vertex_first, vertex_size, std::move(chunk_bounds));
  }
  // With direct writes a chunk is written on its own thread while the next one is built (the write waits
  // on the disk, not the CPU); through the page cache it is written before the next one is built.
  // The buffers are taken once (chunk_buffer_bytes, for the largest chunk) and not cleared: the writers write
  // every byte of their voxels' orders, padding included. (Regrowing and zeroing them per chunk took 3 of
  // the 11 s of a 10M conversion's orders: fresh pages cost much on a virtual machine.)
  std::vector<std::size_t> by_size;  // a chunk's voxels
  BackgroundTask<> writing;
  for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
    auto t0 = Clock::now();
    const std::size_t first = cuts[c], end = cuts[c + 1];
    const std::span<const std::uint8_t> vertices = chunk_vertices->take(c);
    const std::uint64_t base = orders_start(first);
    const int b = plan_.direct_staging_bytes > 0 ? c % 2 : 0;
    if (chunks[b] == nullptr) {
      void* p = std::aligned_alloc(DirectRegionWriter::kBlock, chunk_buffer_bytes(plan_.order_chunk_bytes));
      if (p == nullptr) throw std::bad_alloc();
      own_chunks[b].reset(static_cast<std::uint8_t*>(p));
      chunks[b] = own_chunks[b].get();
    }
    const std::span<std::uint8_t> chunk(chunks[b] + out_->block_lead(VxlStreamWriter::kOrdb, base),
                                        orders_start(end) - base);
    // Largest voxels first, so that the threads finish the chunk at about the same time.
    by_size.resize(end - first);
    std::iota(by_size.begin(), by_size.end(), first);
    std::stable_sort(by_size.begin(), by_size.end(), [&](std::size_t a, std::size_t b) {
      return table_.voxels[a].vertex_count > table_.voxels[b].vertex_count;
    });
    parallel_for(end - first, r.order_threads, [&](std::uint64_t i, unsigned t) {
      if (!writers[t]) writers[t].emplace(job_.order_set, r.max_vertices);
      const std::size_t g = by_size[i];
      write_voxel_orders(r, g, vertices, vertex_start(first), *writers[t], block_ends[t],
                         chunk.data() + (table_.voxels[g].order_offset - base));
    });
    if (writing.valid()) writing.get();  // rethrows a failed write
    std::uint8_t* const block = chunks[b];
    if (plan_.direct_staging_bytes > 0)
      writing = BackgroundTask<>(
          [this, block, chunk] { out_->append_from_block(VxlStreamWriter::kOrdb, block, chunk.size()); });
    else
      out_->append_from_block(VxlStreamWriter::kOrdb, block, chunk.size());
    summary_.orders_seconds += seconds_since(t0);
    report(stage, double(end - r.first) / double(std::max<std::size_t>(1, r.end - r.first)));
  }
  if (writing.valid()) writing.get();
}

// Voxel g's orders at `dst`, from its block in `vertices` (the part of VERT from vertex
// `vertices_first`): the orders sort the positions the file holds. A float32 block's voxline ends are
// copied into `block_ends` (a packed block holds its own).
void StreamingConversion::write_voxel_orders(const VoxelRange& r, std::size_t g, std::span<const std::uint8_t> vertices,
                                             std::uint64_t vertices_first, VoxelOrderWriter& writer,
                                             VoxlineEnds& block_ends, std::uint8_t* dst) {
  VoxelEntry v = table_.voxels[g];
  const std::span<const LevelEntry> row = level_row(table_.levels, g, job_.settings.levels);
  const std::uint64_t at = v.vertex_first - vertices_first;
  v.vertex_first = 0;
  if (!packed()) {
    block_ends.reset(v.vertex_count);
    const std::uint64_t in_range = table_.voxels[g].vertex_first - r.vertex_first;  // ends_ counts from the range
    for (std::uint32_t e = 0; e < v.vertex_count; ++e)
      if (ends_.test(in_range + e)) block_ends.set(e);
    const float* xyz = reinterpret_cast<const float*>(vertices.data()) + 3 * at;
    writer.write(v, row, {xyz, 3 * std::size_t(v.vertex_count)}, block_ends, dst);
    return;
  }
  writer.write_packed(v, row, reinterpret_cast<const std::uint32_t*>(vertices.data()) + at, dst);
}

}  // namespace vxl::streaming
