#include "format/streamline_length.h"

#include <cmath>
#include <limits>
#include <string>

#include "format/base/error.h"

namespace vxl {

double polyline_length(std::span<const float> xyz) {
  double length = 0;
  for (std::size_t i = 3; i + 2 < xyz.size(); i += 3) {
    const double dx = double(xyz[i]) - xyz[i - 3], dy = double(xyz[i + 1]) - xyz[i - 2],
                 dz = double(xyz[i + 2]) - xyz[i - 1];
    length += std::sqrt(dx * dx + dy * dy + dz * dz);
  }
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
  if (!std::isfinite(length) || std::signbit(length))  // no writer stores -0 either
    fail_input(file.path(), file.find_section(section_id("SLEN"))->offset + 4 * streamline,
               "SLEN length of streamline " + std::to_string(streamline) + " is not a finite number ≥ 0");
  return length;
}

}  // namespace vxl
