#include "converter/readers/tck_stream.h"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "converter/readers/regular_file.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/regular_file.h"

namespace vxl {
namespace {

std::int64_t mtime_ns(const struct stat& st) {
  return std::int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
}

}  // namespace

TckStream::TckStream(const std::string& path, std::uint64_t max_header_bytes, std::uint64_t read_buffer_bytes)
    : path_(path) {
  require_regular_file(path);
  // open_regular_file opens with O_NONBLOCK: should the path become a FIFO after the check, it still
  // does not wait for a writer.
  struct stat st {};
  fd_ = open_regular_file(path, st);
  source_.bytes = static_cast<std::uint64_t>(st.st_size);
  mtime_ns_ = mtime_ns(st);
  try {
    // The header is read whole; grow the prefix until it holds the END line.
    std::vector<std::uint8_t> prefix;
    std::uint64_t want = std::min<std::uint64_t>({source_.bytes, 1u << 16, max_header_bytes});
    for (;;) {
      prefix.resize(want);
      read_at(0, prefix.data(), want);
      if (std::optional<MrtrixHeader> h = parse_mrtrix_header(path, prefix, source_.bytes, kTckFile)) {
        header_ = std::move(*h);
        break;
      }
      if (want >= max_header_bytes)
        fail_unsupported(path, "the TCK header is longer than " + std::to_string(max_header_bytes) +
                                   " bytes, more than the memory limit leaves for it; raise --memory-limit");
      want = std::min({source_.bytes, max_header_bytes, want * 4});
    }
    datatype_ = mrtrix_datatype(path, header_.datatype, kTckFile);
    source_.path = path;
    source_.format = "tck";
    source_.dtype = header_.datatype;
    source_.header = header_.fields;
    triplet_bytes_ = header_.datatype.starts_with("Float64") ? 24 : 12;
    window_bytes_ = std::max<std::uint64_t>(1, read_buffer_bytes / triplet_bytes_) * triplet_bytes_;
    window_ = std::make_unique_for_overwrite<std::uint8_t[]>(window_bytes_);
    ::posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);  // a hint: read ahead further
    rewind();
  } catch (...) {  // the destructor does not run for a constructor that throws
    ::close(fd_);
    throw;
  }
}

TckStream::~TckStream() {
  if (fd_ >= 0) ::close(fd_);
}

void TckStream::read_at(std::uint64_t offset, std::uint8_t* dst, std::uint64_t size) {
  while (size > 0) {
    ssize_t n = ::pread(fd_, dst, size, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail_input(path_, offset, std::string("read failed: ") + std::strerror(errno));
    if (n == 0) fail_input(path_, offset, "unexpected end of file (did the file change while it was being read?)");
    dst += n;
    size -= static_cast<std::uint64_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
}

void TckStream::check_unchanged() const {
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || static_cast<std::uint64_t>(st.st_size) != source_.bytes || mtime_ns(st) != mtime_ns_)
    fail_input(path_, std::nullopt,
               "the file changed while it was being converted (--memory-limit reads it several times)");
}

void TckStream::rewind() {
  check_unchanged();
  buffer_used_ = buffer_size_ = 0;
  read_end_ = header_.data_offset;
  state_ = {};
  data_ended_ = false;
  overflowed_ = false;
  streamlines_ = 0;
  if (complete_) return;
  // The first pass hashes the whole file in order: the header here, the rest as it is read.
  hash_ = std::make_unique<Xxh3_128Stream>();
  std::vector<std::uint8_t> header(header_.data_offset);
  read_at(0, header.data(), header.size());
  hash_->update(header.data(), header.size());
}

bool TckStream::fill_buffer() {
  if (read_end_ >= source_.bytes) return false;
  std::uint64_t n = std::min<std::uint64_t>(window_bytes_, source_.bytes - read_end_);
  // Read into one buffer, not mapped: a copy from the page cache costs less than mapping each part anew (page
  // tables filled and torn down per part).
  read_at(read_end_, window_.get(), n);
  // Read the next part while this one is decoded (a hint: the read above waits).
  ::posix_fadvise(fd_, static_cast<off_t>(read_end_ + n), static_cast<off_t>(window_bytes_), POSIX_FADV_WILLNEED);
  if (hash_) hash_->update(window_.get(), n);
  read_end_ += n;
  buffer_size_ = n;
  buffer_used_ = 0;
  return true;
}

bool TckStream::next(Tractogram& batch, std::uint64_t max_points, std::uint64_t max_points_held) {
  batch.positions.clear();
  batch.offsets.assign(1, 0);
  if (data_ended_ || overflowed_) return false;
  const std::uint64_t stop = std::max<std::uint64_t>(1, max_points);
  for (;;) {
    const std::uint64_t whole = (buffer_size_ - buffer_used_) / triplet_bytes_;
    if (whole > 0) {
      const std::uint8_t* p = window_.get() + buffer_used_;
      const std::uint64_t offset = read_end_ - buffer_size_ + buffer_used_;
      const std::uint64_t used = visit_mrtrix_datatype(datatype_, [&]<typename Real, bool kBigEndian>() {
        return tck::decode<Real, kBigEndian>(path_, p, whole, offset, batch, state_, stop);
      });
      buffer_used_ += used * triplet_bytes_;
      if (state_.terminated) break;
      // decode stops right after the streamline that fills the batch
      if (state_.points_in_current == 0 && batch.point_count() + batch.streamline_count() >= stop) {
        streamlines_ += batch.streamline_count();
        return true;
      }
      if (batch.point_count() > max_points_held) {
        overflowed_ = true;
        return false;
      }
    }
    if (!fill_buffer()) break;
  }

  // The end of the data: what read_tck does after its last triplet.
  data_ended_ = true;
  std::vector<std::string> warnings;
  tck::finish(state_, source_.bytes - (read_end_ - buffer_size_ + buffer_used_), batch, warnings);
  streamlines_ += batch.streamline_count();
  if (!complete_) {
    tck::header_warnings(header_, streamlines_, warnings);
    source_.warnings = std::move(warnings);
    while (fill_buffer()) {
    }  // bytes after an Inf terminator count in the hash too
    source_.xxh3_128 = hash_->hex();
    hash_.reset();
    complete_ = true;
  }
  return batch.streamline_count() > 0;
}

}  // namespace vxl
