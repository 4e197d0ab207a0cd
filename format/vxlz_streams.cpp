#include "format/vxlz_streams.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include <zlib.h>

#include "format/base/error.h"

namespace vxl {

std::uint64_t VarintReader::get_long() {
  std::uint64_t v = 0;
  for (int shift = 0;; shift += 7) {
    if (pos_ >= bytes_.size()) fail("stream ends inside or before a value");
    const std::uint8_t b = bytes_[pos_++];
    if (shift == 63 && (b & 0x7E) != 0) fail("varint does not fit in 64 bits");
    v |= std::uint64_t(b & 0x7F) << shift;
    if ((b & 0x80) == 0) return v;
    if (shift == 63) fail("varint longer than 10 bytes");
  }
}

std::span<const std::uint8_t> VarintReader::get_bytes(std::uint64_t n) {
  if (n > bytes_.size() - pos_) fail("stream ends inside a byte string of " + std::to_string(n) + " bytes");
  std::span<const std::uint8_t> s = bytes_.subspan(pos_, n);
  pos_ += n;
  return s;
}

void VarintReader::expect_end() const {
  if (pos_ != bytes_.size()) fail(std::to_string(bytes_.size() - pos_) + " bytes left over after the expected values");
}

void VarintReader::fail(const std::string& what) const {
  fail_input(context_.file, context_.section_offset,
             "section " + context_.section + ", inflated byte " + std::to_string(pos_) + ": " + what);
}

namespace {

// zlib counts in 32-bit uInt: calls `step` (deflate or inflate; its argument says whether this is the last
// of the input) on pieces of at most 1 GiB in and out until it returns other than Z_OK, a call that
// makes no progress ending it as Z_BUF_ERROR. Counts down `in_left` and `out_left`; returns the last code.
template <typename Step>
int zlib_in_pieces(z_stream& z, std::uint64_t& in_left, std::uint64_t& out_left, Step step) {
  int rc = Z_OK;
  while (rc == Z_OK) {
    const uInt in_piece = static_cast<uInt>(std::min<std::uint64_t>(in_left, 1u << 30));
    const uInt out_piece = static_cast<uInt>(std::min<std::uint64_t>(out_left, 1u << 30));
    z.avail_in = in_piece;
    z.avail_out = out_piece;
    rc = step(in_piece == in_left);
    if (rc == Z_OK && in_piece == z.avail_in && out_piece == z.avail_out) rc = Z_BUF_ERROR;  // no progress
    in_left -= in_piece - z.avail_in;
    out_left -= out_piece - z.avail_out;
  }
  return rc;
}

}  // namespace

std::vector<std::uint8_t> deflate_section(std::span<const std::uint8_t> raw, DeflateMode mode) {
  auto fail = [] { throw Error(ErrorKind::Output, "", std::nullopt, "zlib could not compress a package stream"); };
  z_stream z{};
  // Level 6 (zlib's default): level 9 makes these streams <1 % smaller and packing several times slower.
  if (deflateInit2(&z, 6, Z_DEFLATED, 15, 8, mode == DeflateMode::HuffmanOnly ? Z_HUFFMAN_ONLY : Z_DEFAULT_STRATEGY) !=
      Z_OK)
    fail();
  std::vector<std::uint8_t> out(8 + deflateBound(&z, static_cast<uLong>(raw.size())));
  const std::uint64_t raw_size = raw.size();
  std::memcpy(out.data(), &raw_size, 8);
  z.next_in = const_cast<Bytef*>(raw.data());
  z.next_out = out.data() + 8;
  std::uint64_t in_left = raw.size(), out_left = out.size() - 8;
  const int rc =
      zlib_in_pieces(z, in_left, out_left, [&](bool last_in) { return deflate(&z, last_in ? Z_FINISH : Z_NO_FLUSH); });
  deflateEnd(&z);
  if (rc != Z_STREAM_END) fail();
  out.resize(out.size() - out_left);
  return out;
}

std::vector<std::uint8_t> inflate_section(std::span<const std::uint8_t> payload, const StreamContext& context) {
  auto fail = [&](const std::string& what) {
    fail_input(context.file, context.section_offset, "section " + context.section + ": " + what);
  };
  if (payload.size() < 8) fail("shorter than its 8-byte raw size");
  std::uint64_t raw_size;
  std::memcpy(&raw_size, payload.data(), 8);
  const std::uint64_t compressed = payload.size() - 8;
  if (raw_size > 1100 * compressed + 64)
    fail("raw size " + std::to_string(raw_size) + " is more than zlib can expand " + std::to_string(compressed) +
         " bytes to");
  // One spare byte: a stream that inflates to more than raw_size shows itself by filling it (and zlib
  // wants a non-null output pointer even for an empty stream).
  std::vector<std::uint8_t> raw(raw_size + 1);

  z_stream z{};
  if (inflateInit(&z) != Z_OK) throw Error(ErrorKind::Unsupported, context.file, std::nullopt, "zlib could not start");
  z.next_in = const_cast<Bytef*>(payload.data() + 8);
  z.next_out = raw.data();
  std::uint64_t in_left = compressed, out_left = raw.size();
  const int rc = zlib_in_pieces(z, in_left, out_left, [&](bool) { return inflate(&z, Z_NO_FLUSH); });
  inflateEnd(&z);
  const std::uint64_t produced = raw.size() - out_left;
  if (produced > raw_size) fail("zlib stream inflates to more than its raw size " + std::to_string(raw_size));
  if (rc != Z_STREAM_END) fail("zlib stream is damaged or ends early");
  if (produced != raw_size) fail("zlib stream inflates to fewer bytes than its raw size " + std::to_string(raw_size));
  if (in_left != 0) fail("bytes follow the end of the zlib stream");
  raw.pop_back();
  return raw;
}

}  // namespace vxl
