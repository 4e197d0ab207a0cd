// The byte streams of a .vxlz package's exact part (spec §1, §4): varint arrays, and the zlib sections
// that hold them (u64 raw size + one zlib stream).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace vxl {

// Unsigned LEB128 and zigzag, appended to a byte vector.
class VarintWriter {
 public:
  void put(std::uint64_t v) {
    while (v >= 0x80) {
      bytes_.push_back(static_cast<std::uint8_t>(v | 0x80));
      v >>= 7;
    }
    bytes_.push_back(static_cast<std::uint8_t>(v));
  }
  void put_signed(std::int64_t v) { put((static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63)); }
  void put_bytes(const void* data, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(data);
    bytes_.insert(bytes_.end(), b, b + n);
  }
  std::vector<std::uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
};

// Where an inflated stream came from, for error messages: a byte offset inside an inflated stream means
// nothing in the file, so errors name the section (and its file offset) and the position in the stream.
struct StreamContext {
  std::string file;
  std::string section;  // four-letter id
  std::uint64_t section_offset = 0;
};

// Reads varints from an inflated stream; every malformed or missing value throws vxl::Error (Input).
class VarintReader {
 public:
  VarintReader(std::span<const std::uint8_t> bytes, const StreamContext& context) : bytes_(bytes), context_(context) {}
  std::uint64_t get() {
    if (pos_ < bytes_.size() && bytes_[pos_] < 0x80) return bytes_[pos_++];  // most values are one byte
    return get_long();
  }
  std::int64_t get_signed() {
    const std::uint64_t u = get();
    return static_cast<std::int64_t>(u >> 1) ^ -static_cast<std::int64_t>(u & 1);
  }
  std::span<const std::uint8_t> get_bytes(std::uint64_t n);
  void expect_end() const;  // throws when bytes are left over
  [[noreturn]] void fail(const std::string& what) const;

 private:
  std::uint64_t get_long();
  std::span<const std::uint8_t> bytes_;
  std::uint64_t pos_ = 0;
  StreamContext context_;
};

// How a stream is deflated; readers need not know (any zlib stream is valid, spec §1).
enum class DeflateMode {
  Matching,     // zlib level 6: string matching, for streams with repeated runs (the voxline voxels)
  HuffmanOnly,  // entropy coding only (Z_HUFFMAN_ONLY): for streams of numbers that seldom repeat in
                // sequence (counts), smaller than level 6 and an order of magnitude faster
};

// The payload of a zlib section: u64 raw size, then `raw` deflated. Throws vxl::Error (Output) when zlib fails.
std::vector<std::uint8_t> deflate_section(std::span<const std::uint8_t> raw, DeflateMode mode = DeflateMode::Matching);

// Inflates a zlib section payload; throws vxl::Error (Input) naming the section unless it inflates to
// exactly its stated raw size and the stream ends exactly at the end of the payload. The raw size is
// bounded by deflate's largest expansion before anything is allocated (spec §1).
std::vector<std::uint8_t> inflate_section(std::span<const std::uint8_t> payload, const StreamContext& context);

}  // namespace vxl
