#include "converter/readers/gzip_bytes.h"

#include <algorithm>
#include <cstring>
#include <new>

#include "format/base/error.h"

namespace vxl {

bool is_gzip(std::span<const std::uint8_t> file) { return file.size() >= 2 && file[0] == 0x1F && file[1] == 0x8B; }

GzipBytes::GzipBytes(const std::string& path, std::span<const std::uint8_t> compressed,
                     std::vector<std::string>& warnings, std::uint64_t max_inflated, std::string typical)
    : in_(compressed),
      gz_(true),
      path_(path),
      warnings_(&warnings),
      max_inflated_(max_inflated),
      typical_(std::move(typical)) {
  if (inflateInit2(&z_, 16 + MAX_WBITS) != Z_OK) throw std::bad_alloc();  // 16: gzip framing only
  buffer_.resize(kReadBuffer);
}

GzipBytes::~GzipBytes() {
  if (gz_) inflateEnd(&z_);
}

const std::uint8_t* GzipBytes::take(std::size_t n) {
  if (!gz_) {
    if (in_.size() - offset_ < n) return nullptr;
    const std::uint8_t* p = in_.data() + offset_;
    offset_ += n;
    return p;
  }
  while (end_ - begin_ < n && !ended_) refill(n);
  if (end_ - begin_ < n) return nullptr;
  const std::uint8_t* p = buffer_.data() + begin_;
  begin_ += n;
  offset_ += n;
  return p;
}

bool GzipBytes::skip(std::uint64_t n) {
  while (n > 0) {
    const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(n, kReadBuffer));
    if (!take(step)) return false;
    n -= step;
  }
  return true;
}

bool GzipBytes::at_end() {
  if (!gz_) return offset_ == in_.size();
  while (end_ == begin_ && !ended_) refill(1);
  return end_ == begin_;
}

// Inflates more into the buffer, which keeps the bytes not yet taken and makes room for n of them.
void GzipBytes::refill(std::size_t n) {
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (buffer_.size() < std::max(n, kReadBuffer)) buffer_.resize(std::max(n, kReadBuffer));
  z_.next_out = buffer_.data() + end_;
  z_.avail_out = static_cast<uInt>(buffer_.size() - end_);
  while (z_.avail_out > 0 && !ended_) {
    if (z_.avail_in == 0 && in_pos_ < in_.size()) {  // zlib counts input in 32 bits: feed it in slices
      z_.next_in = const_cast<Bytef*>(in_.data() + in_pos_);
      z_.avail_in = static_cast<uInt>(std::min<std::uint64_t>(in_.size() - in_pos_, 1u << 30));
      in_pos_ += z_.avail_in;
    }
    const int r = inflate(&z_, Z_NO_FLUSH);
    const std::uint64_t at = in_pos_ - z_.avail_in;  // offset in the compressed file
    if (r == Z_STREAM_END) {
      member_end();
      continue;
    }
    if (r != Z_OK && r != Z_BUF_ERROR)
      fail_input(path_, at,
                 "corrupt gzip stream after " + std::to_string(inflated()) +
                     " decompressed bytes: " + (z_.msg ? z_.msg : "zlib error " + std::to_string(r)));
    if (z_.avail_in == 0 && in_pos_ == in_.size() && z_.avail_out > 0)
      fail_input(path_, at,
                 "the gzip stream is truncated: it ends without its end-of-stream marker and CRC, after " +
                     std::to_string(inflated()) + " decompressed bytes");
  }
  end_ = buffer_.size() - z_.avail_out;
  if (inflated() > max_inflated_)
    fail_unsupported(path_, "inflates to more than " + std::to_string(max_inflated_) + " bytes, over " +
                                std::to_string(kMaxInflateRatio) + " times its compressed size (" +
                                std::to_string(in_.size()) + " bytes); refused as a likely decompression bomb (" +
                                typical_ + "). To read it anyway, gunzip it first");
}

void GzipBytes::member_end() {
  const std::uint64_t at = in_pos_ - z_.avail_in;
  if (at == in_.size()) {
    ended_ = true;
    return;
  }
  const std::span<const std::uint8_t> rest = in_.subspan(at);
  if (rest.size() >= 2 && rest[0] == 0x1F && rest[1] == 0x8B) {
    inflated_before_reset_ += z_.total_out;
    inflateReset(&z_);
    return;
  }
  if (std::all_of(rest.begin(), rest.end(), [](std::uint8_t b) { return b == 0; })) {
    warnings_->push_back(std::to_string(rest.size()) + " zero bytes of padding after the gzip stream ignored");
    ended_ = true;
    return;
  }
  fail_input(path_, at,
             std::to_string(rest.size()) + " bytes after the end of the gzip stream are not another gzip member");
}

}  // namespace vxl
