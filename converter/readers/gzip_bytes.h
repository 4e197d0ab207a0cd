// A file's bytes in order, handed out a piece at a time: straight from a mapped file, or inflated from its
// gzip member(s) into a small buffer, so that a compressed file is never held inflated whole. The rules
// for a gzipped file (every reader of one follows them):
//   - a zlib error, or a stream that ends without its end-of-stream marker and CRC, is malformed input
//     (vxl::Error, Input) naming the compressed byte offset;
//   - after a member's CRC, another gzip member may follow (concatenated gzip, as gzip -d reads it) or
//     zero padding (ignored, with a warning); anything else is malformed input;
//   - inflating past `max_inflated` bytes is refused (vxl::Error, Unsupported) as a likely bomb.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <zlib.h>

namespace vxl {

bool is_gzip(std::span<const std::uint8_t> file);

// A gzipped file may inflate at most this many times its own size (plus kInflateSlack). Real data
// compress a few times; deflate reaches ~1000x only on repetitive data such as the zeros of a
// decompression bomb, which would otherwise fill memory.
inline constexpr std::uint64_t kMaxInflateRatio = 100;
inline constexpr std::uint64_t kInflateSlack = 1u << 20;
inline constexpr std::uint64_t inflate_cap(std::uint64_t compressed_bytes) {
  return kMaxInflateRatio * compressed_bytes + kInflateSlack;
}

class GzipBytes {
 public:
  explicit GzipBytes(std::span<const std::uint8_t> plain) : in_(plain) {}
  // `typical` completes the bomb message: how much real files of this kind compress.
  GzipBytes(const std::string& path, std::span<const std::uint8_t> compressed, std::vector<std::string>& warnings,
            std::uint64_t max_inflated, std::string typical);
  ~GzipBytes();
  GzipBytes(const GzipBytes&) = delete;
  GzipBytes& operator=(const GzipBytes&) = delete;

  bool compressed() const { return gz_; }
  // The next n bytes (valid until the next call), or nullptr when the stream ends before n more; then
  // left() bytes remained (and stay unconsumed).
  const std::uint8_t* take(std::size_t n);
  // Skips n bytes (inflating them a buffer at a time); false when the stream ends first.
  bool skip(std::uint64_t n);
  bool at_end();
  std::uint64_t left() const { return gz_ ? end_ - begin_ : in_.size() - offset_; }
  std::uint64_t offset() const { return offset_; }  // bytes of the (decompressed) stream taken so far
  // The stream's size where it is known without reading it (a plain file).
  std::optional<std::uint64_t> size() const { return gz_ ? std::nullopt : std::optional<std::uint64_t>(in_.size()); }
  // The offset in the compressed file that zlib has reached (for messages).
  std::uint64_t compressed_offset() const { return gz_ ? in_pos_ - z_.avail_in : offset_; }

 private:
  static constexpr std::size_t kReadBuffer = 1u << 20;

  void refill(std::size_t n);
  void member_end();
  std::uint64_t inflated() const { return z_.total_out + inflated_before_reset_; }

  std::span<const std::uint8_t> in_;
  std::uint64_t offset_ = 0;
  bool gz_ = false;
  std::string path_;
  std::vector<std::string>* warnings_ = nullptr;
  std::uint64_t max_inflated_ = 0;
  std::string typical_;
  z_stream z_{};
  std::uint64_t in_pos_ = 0;  // compressed bytes handed to zlib
  std::vector<std::uint8_t> buffer_;
  std::size_t begin_ = 0, end_ = 0;  // the inflated bytes not yet taken
  bool ended_ = false;
  std::uint64_t inflated_before_reset_ = 0;
};

}  // namespace vxl
