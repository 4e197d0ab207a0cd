#include "converter/readers/voxel_samples.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>

namespace vxl {
namespace {

template <typename T>
T load(const std::uint8_t* p, bool swap, std::size_t unit) {
  std::uint8_t b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap)
    for (std::size_t at = 0; at + unit <= sizeof(T); at += unit) std::reverse(b + at, b + at + unit);
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

template <typename T>
double value(const std::uint8_t* p, bool swap) {
  return static_cast<double>(load<T>(p, swap, sizeof(T)));
}

double sample(SampleType type, bool swap, const std::uint8_t* p) {
  switch (type) {
    case SampleType::kUInt8: return p[0];
    case SampleType::kInt8: return static_cast<std::int8_t>(p[0]);
    case SampleType::kUInt16: return value<std::uint16_t>(p, swap);
    case SampleType::kInt16: return value<std::int16_t>(p, swap);
    case SampleType::kUInt32: return value<std::uint32_t>(p, swap);
    case SampleType::kInt32: return value<std::int32_t>(p, swap);
    case SampleType::kUInt64: return value<std::uint64_t>(p, swap);
    case SampleType::kInt64: return value<std::int64_t>(p, swap);
    case SampleType::kFloat32: return value<float>(p, swap);
    case SampleType::kFloat64: return value<double>(p, swap);
    case SampleType::kFloat128: return static_cast<double>(load<long double>(p, swap, 16));
    case SampleType::kComplex64: return std::abs(load<std::complex<float>>(p, swap, 4));
    case SampleType::kComplex128: return std::abs(load<std::complex<double>>(p, swap, 8));
    case SampleType::kRgb24:
    case SampleType::kRgba32: return (double(p[0]) + p[1] + p[2]) / 3.0;
  }
  return 0.0;
}

}  // namespace

std::size_t sample_bytes(SampleType type) {
  switch (type) {
    case SampleType::kUInt8:
    case SampleType::kInt8: return 1;
    case SampleType::kUInt16:
    case SampleType::kInt16: return 2;
    case SampleType::kUInt32:
    case SampleType::kInt32:
    case SampleType::kFloat32:
    case SampleType::kRgba32: return 4;
    case SampleType::kUInt64:
    case SampleType::kInt64:
    case SampleType::kFloat64:
    case SampleType::kComplex64: return 8;
    case SampleType::kFloat128:
    case SampleType::kComplex128: return 16;
    case SampleType::kRgb24: return 3;
  }
  return 1;
}

std::size_t sample_swap_bytes(SampleType type) {
  switch (type) {
    case SampleType::kComplex64: return 4;
    case SampleType::kComplex128: return 8;
    case SampleType::kRgb24:
    case SampleType::kRgba32: return 1;
    default: return sample_bytes(type);
  }
}

void samples_to_float(SampleType type, bool swap, const std::uint8_t* in, std::size_t n, float* out, double slope,
                      double inter) {
  const std::size_t size = sample_bytes(type);
  for (std::size_t i = 0; i < n; ++i) {
    const float v = static_cast<float>(sample(type, swap, in + i * size) * slope + inter);
    out[i] = std::isfinite(v) ? v : 0.0f;
  }
}

}  // namespace vxl
