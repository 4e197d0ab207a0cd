#include "format/direct_region_writer.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "format/error.h"

namespace vxl {

DirectRegionWriter::DirectRegionWriter(AtomicOutputFile& out, int direct_fd, std::uint64_t offset, std::uint64_t size,
                                       std::uint64_t staging_bytes, std::uint8_t* staging_memory)
    : out_(out),
      direct_fd_(direct_fd),
      end_(offset + size),
      position_(offset),
      staging_bytes_(staging_size(size, staging_bytes)) {
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

void DirectRegionWriter::write_staged() {
  // Whole blocks directly. Staging is written when full (whole blocks) or at the region's end, where the
  // last partial block may hold the next region's bytes: that one goes through the page cache.
  const std::uint64_t whole = staged_ / kBlock * kBlock;
  write_at(staging_.get(), whole, staging_start_);
  if (whole < staged_) out_.pwrite(staging_.get() + whole, staged_ - whole, staging_start_ + whole);
  staged_ = 0;
}

void DirectRegionWriter::write_at(const std::uint8_t* data, std::uint64_t size, std::uint64_t offset) {
  while (size > 0 && direct_fd_ >= 0) {
    const ssize_t n = ::pwrite(direct_fd_, data, size, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EINVAL) {
      direct_fd_ = -1;  // no direct I/O here: the page cache it is
      break;
    }
    if (n < 0)
      throw Error(ErrorKind::Output, out_.path(), std::nullopt, std::string("write failed: ") + std::strerror(errno));
    data += n;
    size -= static_cast<std::uint64_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
  if (size > 0) out_.pwrite(data, size, offset);
}

}  // namespace vxl
