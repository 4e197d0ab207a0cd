#include "converter/pipeline/vertex_sink.h"

#include <stdexcept>
#include <utility>

namespace vxl {

VertexSink::VertexSink(VxlStreamWriter& out, const std::vector<std::array<std::uint64_t, 2>>& blocks,
                       std::uint64_t vertex_bytes, std::uint64_t staging_bytes, std::uint64_t spares,
                       std::uint8_t* pool, std::uint64_t pool_bytes)
    : vertex_bytes_(vertex_bytes) {
  blocks_.resize(blocks.size());
  std::uint8_t* staging = pool;  // the queue's spares, then each block's staging, one after another
  std::vector<std::uint8_t*> spare_stagings;
  for (std::uint64_t k = 0; k < spares; ++k, staging += staging_bytes) spare_stagings.push_back(staging);
  queue_ = out.write_queue(std::move(spare_stagings), staging_bytes);
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const auto [first, end] = blocks[k];
    if (end <= first) continue;
    const std::uint64_t size = DirectRegionWriter::staging_size((end - first) * vertex_bytes, staging_bytes);
    if (std::uint64_t(staging - pool) + size > pool_bytes)
      throw std::logic_error("StreamingConversion: the blocks' staging outgrows its pool");
    blocks_[k] = out.region_writer(VxlStreamWriter::kVert, first * vertex_bytes, (end - first) * vertex_bytes,
                                   staging_bytes, staging, queue_.get());
    staging += size;
  }
}

void VertexSink::finish() {
  if (queue_) queue_->finish();  // rethrows a failed write
  blocks_.clear();
}

}  // namespace vxl
