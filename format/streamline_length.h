// The length of a streamline as SLEN stores it (spec §5.15) and as a selection's --min-length/--max-length
// measure it: the sum of its segments' Euclidean lengths, as MRtrix tckedit measures it (up to its rounding). One
// definition, compiled once (without fused multiply-add), so that the converter's lengths, verify's and a reader's of a
// file without SLEN agree to the bit.
#pragma once

#include <cstdint>
#include <span>

#include "format/vxl_file.h"

namespace vxl {

// The polyline's length in mm: each segment's length from its float32 end points in double, summed in
// order in double (0 for fewer than two points).
double polyline_length(std::span<const float> xyz);
// One step of polyline_length, from point a to point b (3 floats each), and `length` with the steps from `last` to the
// first of `n` points and on along them added one by one: polyline_length is its steps summed in order, so that a
// reader with a streamline's points in pieces sums the same steps. Compiled here, with polyline_length.
double polyline_step(const float* a, const float* b);
double polyline_extend(double length, const float* last, const float* xyz, std::size_t n);

// The length SLEN stores for those points: polyline_length rounded to float32.
inline float stored_length_of(std::span<const float> xyz) { return static_cast<float>(polyline_length(xyz)); }

// The length as MRtrix's tckedit measures it for -minlength and -maxlength, to the bit: each segment's end points
// subtracted, squared and summed as x² + (y² + z²) (Eigen's unrolled sum), and square-rooted in float32, the segments
// added in order to a float32 sum; NaN for no points. It differs from stored_length_of by up to (points + 5) float32
// roundings of the length (spec §5.15), which is how a selection knows when SLEN decides a limit as tckedit would.
float float32_polyline_length(std::span<const float> xyz);

// Streamline s's length from the file's SLEN, which it must have: throws vxl::Error (Input, naming the file and
// the byte) for a value that is not finite, has its sign bit set (-0 included), or is longer than all the
// file's points could make within its bounds. (A caller that trusts the values checks the section's checksum.)
double stored_length(const VxlFile& file, std::uint64_t streamline);

}  // namespace vxl
