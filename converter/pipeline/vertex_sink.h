// Where the streamed conversion's placing pass puts each voxline's vertices: into the range's part of VERT
// held in memory (a mapping of the output, or a buffer written once the pass ends), or, where VERT is written
// block by block, into a staging of each (voxel, level) block's own that goes to the file past the page cache
// whenever it is full (DirectRegionWriter, through a DirectWriteQueue's background writer).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "format/base/direct_region_writer.h"
#include "format/base/direct_write_queue.h"
#include "format/vxl_stream_writer.h"

namespace vxl {

class VertexSink {
 public:
  // Held: `window` is the range's part of VERT, from the range's first vertex.
  VertexSink(std::span<std::uint8_t> window, std::uint64_t vertex_bytes)
      : window_(window), vertex_bytes_(vertex_bytes) {}
  // Block by block into `out`'s VERT: blocks[k] = {first, end} vertex (end == first: a block with no vertices
  // here). The queue's `spares` stagings, then each block's, are carved one after another out of `pool`
  // (`pool_bytes`, block-aligned), `staging_bytes` each at most.
  VertexSink(VxlStreamWriter& out, const std::vector<std::array<std::uint64_t, 2>>& blocks, std::uint64_t vertex_bytes,
             std::uint64_t staging_bytes, std::uint64_t spares, std::uint8_t* pool, std::uint64_t pool_bytes);

  // Puts `count` vertices from `from` at vertex `at` of the range, in block `block`.
  void put(std::size_t block, std::uint64_t at, const std::uint8_t* from, std::uint64_t count) {
    if (!blocks_.empty())
      blocks_[block]->append({from, count * vertex_bytes_});
    else
      std::copy_n(from, count * vertex_bytes_, window_.data() + at * vertex_bytes_);
  }
  // Waits until every staging is written (each block wrote its last bytes with its last put); rethrows the
  // first failed write.
  void finish();

 private:
  std::span<std::uint8_t> window_;  // held
  std::uint64_t vertex_bytes_;
  std::unique_ptr<DirectWriteQueue> queue_;                  // block by block
  std::vector<std::unique_ptr<DirectRegionWriter>> blocks_;  // block by block; after queue_: destroyed first
};

}  // namespace vxl
