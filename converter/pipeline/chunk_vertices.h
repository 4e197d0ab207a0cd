// Where the streamed conversion's orders find a range's vertices, a chunk of voxels at a time: the range's
// part of VERT held in memory (mapped), or VERT read back from the output (VxlStreamWriter::read_back) when it
// was written block by block, the next chunk's read in the background while one is ordered.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "format/base/parallel.h"
#include "format/vxl_stream_writer.h"

namespace vxl {

class ChunkVertices {
 public:
  // Chunk c holds vertices [chunk_bounds[c], chunk_bounds[c + 1]) of `vertex_bytes` each.
  // Held: `range_vertices` holds the vertices from `range_first` on.
  ChunkVertices(std::span<const std::uint8_t> range_vertices, std::uint64_t range_first, std::uint64_t vertex_bytes,
                std::vector<std::uint64_t> chunk_bounds)
      : held_(range_vertices),
        range_first_(range_first),
        vertex_bytes_(vertex_bytes),
        bounds_(std::move(chunk_bounds)) {}
  // Read back: VERT's next bytes from `out` into buffers[c % 2] (each VxlStreamWriter::read_back_bytes of the
  // largest chunk); the first chunk's read starts at once.
  ChunkVertices(VxlStreamWriter& out, std::array<std::span<std::uint8_t>, 2> buffers, std::uint64_t vertex_bytes,
                std::vector<std::uint64_t> chunk_bounds)
      : out_(&out), buffers_(buffers), vertex_bytes_(vertex_bytes), bounds_(std::move(chunk_bounds)) {
    if (bounds_.size() > 1) next_ = fetch(0);
  }
  ChunkVertices(const ChunkVertices&) = delete;  // the background read refers to this object
  ChunkVertices& operator=(const ChunkVertices&) = delete;

  // Chunk c's vertices, for c = 0, 1, ... in turn (read back, VERT is read in order); valid until the chunk
  // after next is taken.
  std::span<const std::uint8_t> take(std::size_t c) {
    if (out_ == nullptr) return load(c);
    const std::span<const std::uint8_t> vertices = next_.get();
    if (c + 2 < bounds_.size()) next_ = fetch(c + 1);
    return vertices;
  }

 private:
  std::span<const std::uint8_t> load(std::size_t c) {
    const std::uint64_t from = bounds_[c], to = bounds_[c + 1];
    if (out_ == nullptr) return held_.subspan((from - range_first_) * vertex_bytes_, (to - from) * vertex_bytes_);
    return out_->read_back(VxlStreamWriter::kVert, (to - from) * vertex_bytes_, buffers_[c % 2]);
  }
  BackgroundTask<std::span<const std::uint8_t>> fetch(std::size_t c) {
    return BackgroundTask<std::span<const std::uint8_t>>([this, c] { return load(c); });
  }

  std::span<const std::uint8_t> held_;  // held
  std::uint64_t range_first_ = 0;
  VxlStreamWriter* out_ = nullptr;  // read back
  std::array<std::span<std::uint8_t>, 2> buffers_;
  std::uint64_t vertex_bytes_;
  std::vector<std::uint64_t> bounds_;
  BackgroundTask<std::span<const std::uint8_t>> next_;  // last: joined first
};

}  // namespace vxl
