#include "format/streamline_length.h"

#include <cmath>
#include <limits>
#include <string>

#include "format/base/error.h"

namespace vxl {

double polyline_step(const float* a, const float* b) {
  const double dx = double(b[0]) - a[0], dy = double(b[1]) - a[1], dz = double(b[2]) - a[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

double polyline_extend(double length, const float* last, const float* xyz, std::size_t n) {
  for (const float* p = xyz; p != xyz + 3 * n; last = p, p += 3) length += polyline_step(last, p);
  return length;
}

double polyline_length(std::span<const float> xyz) {
  double length = 0;
  for (std::size_t i = 3; i + 2 < xyz.size(); i += 3) length += polyline_step(&xyz[i - 3], &xyz[i]);
  return length;
}

float float32_polyline_length(std::span<const float> xyz) {
  if (xyz.size() < 3) return std::numeric_limits<float>::quiet_NaN();
  float length = 0;
  for (std::size_t i = 3; i + 2 < xyz.size(); i += 3) {
    const float dx = xyz[i] - xyz[i - 3], dy = xyz[i + 1] - xyz[i - 2], dz = xyz[i + 2] - xyz[i - 1];
    length += std::sqrt(dx * dx + (dy * dy + dz * dz));
  }
  return length;
}

double stored_length(const VxlFile& file, std::uint64_t streamline) {
  const float length = file.streamline_lengths()[streamline];
  auto refuse = [&](const std::string& why) {
    fail_input(file.path(), file.find_section(section_id("SLEN"))->offset + 4 * streamline,
               "SLEN length of streamline " + std::to_string(streamline) + " " + why);
  };
  if (!std::isfinite(length) || std::signbit(length)) refuse("is not a finite number ≥ 0");  // nor -0
  // No streamline is longer than all the file's points could make: each segment within the bounds' diagonal.
  const MetaSection& m = file.meta();
  const double diagonal = std::hypot(m.bounds_max[0] - m.bounds_min[0], m.bounds_max[1] - m.bounds_min[1],
                                     m.bounds_max[2] - m.bounds_min[2]);
  if (double(length) > double(m.point_count) * diagonal * (1 + 0x1p-20) + 1e-6)
    refuse("(" + std::to_string(length) + " mm) is longer than the file's " + std::to_string(m.point_count) +
           " points within its bounds can make");
  return length;
}

}  // namespace vxl
