#include "format/base/direct_region_writer.h"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "format/base/error.h"

namespace vxl {

DirectRegionWriter::DirectRegionWriter(AtomicOutputFile& out, int direct_fd, std::uint64_t offset, std::uint64_t size,
                                       std::uint64_t staging_bytes, std::uint8_t* staging_memory,
                                       DirectWriteQueue* queue)
    : out_(out),
      direct_fd_(direct_fd),
      end_(offset + size),
      position_(offset),
      staging_bytes_(staging_size(size, staging_bytes)),
      queue_(queue) {
  if (queue != nullptr && staging_memory == nullptr)
    throw std::logic_error("DirectRegionWriter: a queue swaps staging buffers: they must be the caller's");
  // A staging that can fill before the region's end is swapped for a spare of the queue's size.
  if (queue != nullptr && staging_bytes_ > queue->buffer_bytes())
    throw std::logic_error("DirectRegionWriter: a staging larger than the queue's buffers");
  if (staging_memory != nullptr) staging_ = {staging_memory, [](void*) {}};
}

std::uint64_t DirectRegionWriter::staging_size(std::uint64_t size, std::uint64_t staging_bytes) {
  // A region of `size` bytes stages at most the blocks it may touch: its size rounded up to blocks, and one more
  // for where it may start inside a block (the staging begins on the block's boundary).
  const std::uint64_t most = (size + kBlock - 1) / kBlock * kBlock + (size > 0 ? kBlock : 0);
  return std::max<std::uint64_t>(kBlock, std::min(most, (staging_bytes + kBlock - 1) / kBlock * kBlock));
}

void DirectRegionWriter::append(std::span<const std::uint8_t> bytes) {
  if (bytes.size() > end_ - position_) throw std::logic_error("DirectRegionWriter::append: past the region's end");
  while (!bytes.empty()) {
    ensure_staging();
    if (staged_ == 0) start_staging();
    const std::uint64_t n = std::min<std::uint64_t>(bytes.size(), staging_bytes_ - staged_);
    std::memcpy(staging_.get() + staged_, bytes.data(), n);
    staged_ += n;
    position_ += n;
    bytes = bytes.subspan(n);
    if (staged_ == staging_bytes_) write_staged();
  }
  if (position_ == end_ && staged_ > 0) write_staged();
}

void DirectRegionWriter::ensure_staging() {
  if (staging_) return;
  void* p = std::aligned_alloc(kBlock, staging_bytes_);
  if (p == nullptr) throw std::bad_alloc();
  staging_ = {static_cast<std::uint8_t*>(p), std::free};
}

void DirectRegionWriter::start_staging() {
  // A staging starts on a block boundary. Where the region starts inside a block (one it shares with its
  // neighbour), the staging's first bytes stand for the neighbour's and are skipped when it is written: that
  // block's bytes go through the page cache then, with the staging, rather than at once from the appending
  // thread (a buffered write waits for the file's direct writes in flight: 10.8k such waits held the 10M set's
  // placing pass).
  skip_ = position_ % kBlock;
  staging_start_ = position_ - skip_;
  staged_ = skip_;
}

void DirectRegionWriter::append_from_block(std::uint8_t* block, std::uint64_t size) {
  if (queue_ != nullptr) throw std::logic_error("DirectRegionWriter::append_from_block: not with a queue");
  if (reinterpret_cast<std::uintptr_t>(block) % kBlock != 0)
    throw std::logic_error("DirectRegionWriter::append_from_block: a block that is not aligned");
  if (size > end_ - position_) throw std::logic_error("DirectRegionWriter::append_from_block: past the region's end");
  if (size == 0) return;
  const std::uint64_t lead = block_lead();
  std::uint64_t skip = lead;  // nothing staged: the region starts in this block, after its neighbour's bytes
  if (staged_ > 0) {
    // What is staged: its whole blocks written, the rest (the start of the block the bytes start in) put before
    // them, with what of it is the neighbour's (the region's first block still staged).
    const std::uint64_t whole_staged = staged_ - lead;
    if (whole_staged > 0) {
      write_blocks(out_, direct_fd_, staging_.get(), whole_staged, staging_start_, skip_);
      skip_ = 0;
    }
    std::memcpy(block, staging_.get() + whole_staged, lead);
    skip = skip_;
  }
  const std::uint64_t at = position_ - lead, total = lead + size;  // `at`: block-aligned
  position_ += size;
  staged_ = 0;
  // The last bytes go at once; otherwise the partial block at the end stays staged for the next append.
  const std::uint64_t whole = position_ == end_ ? total : total / kBlock * kBlock;
  if (whole > 0) write_blocks(out_, direct_fd_, block, whole, at, skip);
  if (whole == total) return;
  ensure_staging();
  std::memcpy(staging_.get(), block + whole, total - whole);
  staging_start_ = at + whole;
  staged_ = total - whole;
  skip_ = whole > 0 ? 0 : skip;
}

void DirectRegionWriter::write_staged() {
  // Staging is written when full (whole blocks) or at the region's end.
  const bool last = position_ == end_;
  if (queue_ == nullptr) {
    write_blocks(out_, direct_fd_, staging_.get(), staged_, staging_start_, skip_);
  } else {
    // The queue writes it while the caller goes on with a spare (none needed after the last bytes). A spare,
    // or a staging of the spares' size, becomes a spare again once written.
    const bool recycle = staging_is_spare_ || staging_bytes_ == queue_->buffer_bytes();
    std::uint8_t* spare = queue_->submit(staging_.release(), staged_, staging_start_, skip_, recycle, !last);
    staging_ = {spare, [](void*) {}};
    staging_is_spare_ = spare != nullptr;
  }
  staged_ = 0;
  skip_ = 0;
}

void DirectRegionWriter::write_blocks(AtomicOutputFile& out, int& direct_fd, const std::uint8_t* data,
                                      std::uint64_t size, std::uint64_t offset, std::uint64_t skip) {
  if (skip > 0) {  // the first block, from byte `skip` on, through the page cache (its start is not ours)
    out.pwrite(data + skip, std::min(size, kBlock) - skip, offset + skip);
    if (size <= kBlock) return;
    data += kBlock;
    size -= kBlock;
    offset += kBlock;
  }
  // Whole blocks directly; a last partial block may hold the next region's bytes: through the page cache.
  std::uint64_t whole = size / kBlock * kBlock;
  const std::uint8_t* tail = data + whole;
  while (whole > 0 && direct_fd >= 0) {
    const ssize_t n = ::pwrite(direct_fd, data, whole, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EINVAL) {
      direct_fd = -1;  // no direct I/O here: the page cache it is
      break;
    }
    if (n < 0)
      throw Error(ErrorKind::Output, out.path(), std::nullopt, std::string("write failed: ") + std::strerror(errno));
    data += n;
    whole -= static_cast<std::uint64_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
  if (whole > 0) out.pwrite(data, whole, offset);
  if (size % kBlock > 0) out.pwrite(tail, size % kBlock, offset + whole);
}

}  // namespace vxl
