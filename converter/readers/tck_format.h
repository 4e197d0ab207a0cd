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
#include "format/base/error.h"

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
  // Little-endian float32 on a little-endian machine (what MRtrix writes): a run of points whose
  // coordinates are all finite is copied as it is, a run at a time; the loop below takes what ends it.
  constexpr bool kVerbatim = std::is_same_v<Real, float> && kBigEndian == (std::endian::native == std::endian::big);
  for (std::uint64_t i = 0; i < n; ++i, p += kTriplet) {
    if constexpr (kVerbatim) {
      auto finite = [](const std::uint8_t* q) {
        std::uint32_t u[3];
        std::memcpy(u, q, sizeof u);
        constexpr std::uint32_t kExponent = 0x7F800000u;  // all ones: Inf or NaN
        return ((u[0] & kExponent) != kExponent) & ((u[1] & kExponent) != kExponent) &
               ((u[2] & kExponent) != kExponent);
      };
      std::uint64_t run = 0;
      while (i + run < n && finite(p + run * kTriplet)) ++run;
      if (run > 0) {
        const std::size_t at = t.positions.size();
        t.positions.resize(at + 3 * run);
        std::memcpy(t.positions.data() + at, p, run * kTriplet);
        s.points_in_current += run;
        i += run;
        p += run * kTriplet;
        if (i == n) break;
      }
    }
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
