// The voxel value types of the image formats, converted to float a block at a time: the reader takes
// the file's bytes in its own type and widens only into the destination, never the whole image at once.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vxl {

enum class SampleType {
  kUInt8,
  kInt8,
  kUInt16,
  kInt16,
  kUInt32,
  kInt32,
  kUInt64,
  kInt64,
  kFloat32,
  kFloat64,
  kFloat128,  // kFloat128: long double (NIfTI's FLOAT128 on x86-64)
  kComplex64,
  kComplex128,  // their magnitude
  kRgb24,
  kRgba32,  // the mean of R, G and B
};

// Bytes per sample, and the size of the units whose byte order the file may have swapped.
std::size_t sample_bytes(SampleType type);
std::size_t sample_swap_bytes(SampleType type);

// Converts n samples at `in` (any alignment; byte-swapped when `swap`) to float at `out`, as
// value * slope + inter (slope 1, inter 0: unscaled); NaN and infinities become 0.
void samples_to_float(SampleType type, bool swap, const std::uint8_t* in, std::size_t n, float* out, double slope = 1.0,
                      double inter = 0.0);

}  // namespace vxl
