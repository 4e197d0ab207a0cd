// Length limits as MRtrix tckedit applies them, to the bit: the thresholds it builds from -minlength, -maxlength and
// the source header's step_size and downsample_factor, and its float32 length (format/streamline_length.h).
//
// tckedit keeps a streamline when min ≤ length ≤ max in float32, where min and max are the options (0 and +inf
// when absent, each rounded to float32) widened by error_margin × step_size: error_margin is 0.1, or
// 0.5 / downsample_factor when the header has one, and the widening applies only when step_size reads as a finite
// float32 (so a negative step_size narrows the limits, and a downsample_factor of 0 opens them completely). A
// header value reads as MRtrix's to<float> reads it: its lines joined (a repeated key gives two lines, which do not
// read as one number), '#' comments cut, then one whole number or nan/inf. A step_size that does not read is no
// step_size; a downsample_factor that does not read makes tckedit refuse the file, and so does select.
#pragma once

#include <limits>
#include <optional>
#include <string_view>

#include "format/vxl_file.h"

namespace vxl {

struct LengthLimits {
  float min = 0;
  float max = std::numeric_limits<float>::infinity();

  // NaN (no points) fails both comparisons, as does everything when a limit is NaN.
  bool keeps(float length) const { return length <= max && length >= min; }
  // Every streamline with points is kept: no length needs measuring.
  bool keep_every_length() const { return min <= 0 && max == std::numeric_limits<float>::infinity(); }
};

// Throws vxl::Error (Input, naming the file) for a downsample_factor that tckedit cannot read, when the limits need it.
LengthLimits tckedit_length_limits(const VxlFile& file, std::optional<double> min_length,
                                   std::optional<double> max_length);

// MRtrix's to<float>: surrounding white space stripped, then the whole text one float32 as a C++ stream reads it
// (out of range: no number), or nan/-nan/inf/-inf in any case; std::nullopt otherwise.
std::optional<float> mrtrix_float(std::string_view text);

}  // namespace vxl
