// TCK reader (MRtrix3 tracks file).
//
// Coordinate convention: TCK stores world coordinates, RAS mm, as-is; we convert to float32 (exact for
// Float32 files, rounded to nearest for Float64 files: spec §8).
//
// Layout: text header "mrtrix tracks" / "key: value" lines (keys may repeat) / "END"; the data starts at
// the byte offset in "file: . OFFSET". Data: xyz triplets; a triplet whose x is NaN ends a streamline, one
// whose x is Inf ends the file. Like MRtrix we tolerate a missing Inf terminator at EOF, and trust the data
// over a stale "count".
#include <bit>
#include <cmath>
#include <cstring>
#include <string_view>

#include "checksum.h"
#include "error.h"
#include "mapped_file.h"
#include "mrtrix_header.h"
#include "read_tractogram.h"

namespace vxl {
namespace {

template <typename Real, bool kBigEndian>
Real load(const std::uint8_t* p) {
  using Bits = std::conditional_t<sizeof(Real) == 4, std::uint32_t, std::uint64_t>;
  Bits bits;
  std::memcpy(&bits, p, sizeof bits);
  if constexpr (kBigEndian) {
    if constexpr (sizeof(Bits) == 4) bits = __builtin_bswap32(bits);
    else bits = __builtin_bswap64(bits);
  }
  return std::bit_cast<Real>(bits);
}

// Walks the data triplets, filling t. Returns the number of bytes consumed.
template <typename Real, bool kBigEndian>
void read_points(const std::string& path, std::span<const std::uint8_t> bytes, std::uint64_t offset, Tractogram& t) {
  constexpr std::size_t kTriplet = 3 * sizeof(Real);
  const std::uint64_t available = (bytes.size() - offset) / kTriplet;
  t.positions.reserve(3 * available);
  const std::uint8_t* p = bytes.data() + offset;
  bool terminated = false;
  std::uint64_t points_in_current = 0;
  for (std::uint64_t i = 0; i < available; ++i, p += kTriplet) {
    Real x = load<Real, kBigEndian>(p), y = load<Real, kBigEndian>(p + sizeof(Real)),
         z = load<Real, kBigEndian>(p + 2 * sizeof(Real));
    if (std::isnan(x)) {  // end of streamline
      t.offsets.push_back(t.point_count());
      points_in_current = 0;
      continue;
    }
    if (std::isinf(x)) {  // end of file
      terminated = true;
      break;
    }
    if (!std::isfinite(y) || !std::isfinite(z))
      fail_input(path, offset + i * kTriplet, "non-finite coordinate inside a streamline (only x marks NaN/Inf delimiters)");
    t.positions.push_back(static_cast<float>(x));
    t.positions.push_back(static_cast<float>(y));
    t.positions.push_back(static_cast<float>(z));
    ++points_in_current;
  }
  if (!terminated) {
    std::uint64_t trailing = (bytes.size() - offset) % kTriplet;
    std::string w = "no Inf terminator before end of file (tolerated, as MRtrix does)";
    if (trailing != 0) w += "; " + std::to_string(trailing) + " trailing bytes ignored";
    t.source.warnings.push_back(w);
    if (points_in_current > 0) {
      t.offsets.push_back(t.point_count());
      t.source.warnings.push_back("last streamline (" + std::to_string(points_in_current) +
                                  " points) has no NaN delimiter: kept");
    }
  } else if (points_in_current > 0) {
    // MRtrix writes a NaN before the Inf; without it the points still form a streamline.
    t.offsets.push_back(t.point_count());
  }
}

}  // namespace

Tractogram read_tck(const std::string& path) {
  MappedFile file(path);
  MrtrixHeader h = parse_mrtrix_header(path, file.bytes(), "mrtrix tracks");
  Tractogram t;
  t.source.path = path;
  t.source.format = "tck";
  t.source.dtype = h.datatype;
  t.source.bytes = file.size();
  t.source.xxh3_128 = xxh3_128_hex(file.data(), file.size());
  t.source.header = h.fields;

  const std::string& dt = h.datatype;
  if (dt == "Float32LE") read_points<float, false>(path, file.bytes(), h.data_offset, t);
  else if (dt == "Float32BE") read_points<float, true>(path, file.bytes(), h.data_offset, t);
  else if (dt == "Float64LE") read_points<double, false>(path, file.bytes(), h.data_offset, t);
  else if (dt == "Float64BE") read_points<double, true>(path, file.bytes(), h.data_offset, t);
  else fail_unsupported(path, "TCK datatype '" + dt + "' (expected Float32LE, Float32BE, Float64LE or Float64BE)");

  if (dt.starts_with("Float64"))
    t.source.warnings.push_back("Float64 coordinates rounded to float32 (spec §8)");
  if (h.count && *h.count != t.streamline_count())
    t.source.warnings.push_back("header count " + std::to_string(*h.count) + " disagrees with the data (" +
                                std::to_string(t.streamline_count()) + " streamlines): the data is trusted");
  return t;
}

}  // namespace vxl
