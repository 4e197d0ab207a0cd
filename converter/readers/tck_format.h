// Pieces of the TCK reader shared by read_tck (whole file in memory) and TckStream (bounded memory), so
// that both read a file identically: header, triplet decoding, and the warnings about the data's end.
// See read_tck.cpp for the format.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "converter/readers/mrtrix_header.h"
#include "converter/tractogram.h"
#include "format/error.h"

namespace vxl::tck {

// Where decoding stands between calls.
struct DecodeState {
  std::uint64_t points_in_current = 0;  // points of the streamline not yet closed by a NaN
  bool terminated = false;              // an Inf triplet was seen: the data has ended
  // The byte offset of that triplet when it is not (Inf, Inf, Inf), as MRtrix writes it: a damaged point?
  std::optional<std::uint64_t> partial_terminator;
};

// Decodes up to `n` triplets at `p` (the first at byte `offset` of the file) into `t`: points are
// appended, a NaN delimiter closes a streamline (t.offsets), an Inf one ends the data. Returns early,
// right after a streamline is closed, once `t` holds `stop_items` points and streamlines together (the
// streamlines count too: a file of delimiters alone is a file of empty streamlines). Returns the number
// of triplets consumed (the terminator included).
template <typename Real, bool kBigEndian>
std::uint64_t decode(const std::string& path, const std::uint8_t* p, std::uint64_t n, std::uint64_t offset,
                     Tractogram& t, DecodeState& s, std::uint64_t stop_items) {
  constexpr std::size_t kTriplet = 3 * sizeof(Real);
  for (std::uint64_t i = 0; i < n; ++i, p += kTriplet) {
    Real x = load_mrtrix_value<Real, kBigEndian>(p), y = load_mrtrix_value<Real, kBigEndian>(p + sizeof(Real)),
         z = load_mrtrix_value<Real, kBigEndian>(p + 2 * sizeof(Real));
    if (std::isnan(x)) {  // end of streamline
      t.offsets.push_back(t.point_count());
      s.points_in_current = 0;
      if (t.point_count() + t.streamline_count() >= stop_items) return i + 1;
      continue;
    }
    if (std::isinf(x)) {  // end of file
      s.terminated = true;
      if (!std::isinf(y) || !std::isinf(z)) s.partial_terminator = offset + i * kTriplet;
      return i + 1;
    }
    if (!std::isfinite(y) || !std::isfinite(z))
      fail_input(path, offset + i * kTriplet,
                 "non-finite coordinate inside a streamline (only x marks NaN/Inf delimiters)");
    t.positions.push_back(static_cast<float>(x));
    t.positions.push_back(static_cast<float>(y));
    t.positions.push_back(static_cast<float>(z));
    ++s.points_in_current;
  }
  return n;
}

// After the last triplet: closes a streamline left open (adding it to `t`) and appends the warnings
// about the end of the data. `trailing` is the number of bytes after the last triplet decode consumed
// (after the terminator, or the part of a triplet at the end of the file).
void finish(const DecodeState& s, std::uint64_t trailing, Tractogram& t, std::vector<std::string>& warnings);

// The warnings about the header that need the whole data (appended after finish()'s).
void header_warnings(const MrtrixHeader& h, std::uint64_t streamlines, std::vector<std::string>& warnings);

}  // namespace vxl::tck
