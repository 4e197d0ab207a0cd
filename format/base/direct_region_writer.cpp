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
  // A region of `size` bytes stages at most size rounded up to blocks (its first partial block is
  // written straight away).
  const std::uint64_t most = (size + kBlock - 1) / kBlock * kBlock;
  return std::max<std::uint64_t>(kBlock, std::min(most, (staging_bytes + kBlock - 1) / kBlock * kBlock));
}

void DirectRegionWriter::append(std::span<const std::uint8_t> bytes) {
  if (bytes.size() > end_ - position_) throw std::logic_error("DirectRegionWriter::append: past the region's end");
  // The block the region starts in may hold its neighbour's bytes too: written through the page cache.
  const std::uint64_t first_block = (position_ + kBlock - 1) / kBlock * kBlock;
  if (staged_ == 0 && position_ < first_block) {
    const std::uint64_t n = std::min<std::uint64_t>(bytes.size(), first_block - position_);
    out_.pwrite(bytes.data(), n, position_);
    position_ += n;
    bytes = bytes.subspan(n);
  }
  while (!bytes.empty()) {
    if (!staging_) {
      void* p = std::aligned_alloc(kBlock, staging_bytes_);
      if (p == nullptr) throw std::bad_alloc();
      staging_ = {static_cast<std::uint8_t*>(p), std::free};
    }
    if (staged_ == 0) staging_start_ = position_;
    const std::uint64_t n = std::min<std::uint64_t>(bytes.size(), staging_bytes_ - staged_);
    std::memcpy(staging_.get() + staged_, bytes.data(), n);
    staged_ += n;
    position_ += n;
    bytes = bytes.subspan(n);
    if (staged_ == staging_bytes_) write_staged();
  }
  if (position_ == end_ && staged_ > 0) write_staged();
}

void DirectRegionWriter::append_from_block(std::uint8_t* block, std::uint64_t size) {
  if (queue_ != nullptr) throw std::logic_error("DirectRegionWriter::append_from_block: not with a queue");
  if (reinterpret_cast<std::uintptr_t>(block) % kBlock != 0)
    throw std::logic_error("DirectRegionWriter::append_from_block: a block that is not aligned");
  if (size > end_ - position_) throw std::logic_error("DirectRegionWriter::append_from_block: past the region's end");
  std::uint64_t lead = block_lead();
  if (staged_ == 0 && lead != 0) {  // the region's first block, shared with its neighbour: through append
    const std::uint64_t n = std::min(size, kBlock - lead);
    append({block + lead, n});
    block += kBlock;
    size -= n;
    lead = 0;
  }
  if (size == 0) return;
  // What is staged: its whole blocks written, the rest (the lead of the block the bytes start in) put before them.
  if (staged_ > lead) {
    write_blocks(out_, direct_fd_, staging_.get(), staged_ - lead, staging_start_);
    staging_start_ += staged_ - lead;
  }
  if (lead > 0) std::memcpy(block, staging_.get() + (staged_ - lead), lead);
  staged_ = 0;
  const std::uint64_t at = position_ - lead, total = lead + size;  // `at`: block-aligned
  position_ += size;
  const std::uint64_t whole = position_ == end_ ? total : total / kBlock * kBlock;  // the last bytes go at once
  write_blocks(out_, direct_fd_, block, whole, at);
  if (whole == total) return;
  // The partial block at the end stays staged for the next append.
  if (!staging_) {
    void* p = std::aligned_alloc(kBlock, staging_bytes_);
    if (p == nullptr) throw std::bad_alloc();
    staging_ = {static_cast<std::uint8_t*>(p), std::free};
  }
  std::memcpy(staging_.get(), block + whole, total - whole);
  staging_start_ = at + whole;
  staged_ = total - whole;
}

void DirectRegionWriter::write_staged() {
  // Staging is written when full (whole blocks) or at the region's end.
  const bool last = position_ == end_;
  if (queue_ == nullptr) {
    write_blocks(out_, direct_fd_, staging_.get(), staged_, staging_start_);
  } else {
    // The queue writes it while the caller goes on with a spare (none needed after the last bytes).
    std::uint8_t* spare =
        queue_->submit(staging_.release(), staged_, staging_start_, staging_bytes_ == queue_->buffer_bytes(), !last);
    staging_ = {spare, [](void*) {}};
  }
  staged_ = 0;
}

void DirectRegionWriter::write_blocks(AtomicOutputFile& out, int& direct_fd, const std::uint8_t* data,
                                      std::uint64_t size, std::uint64_t offset) {
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
