#include "converter/voxel_size_auto.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace vxl {
namespace {

constexpr double kTargetVerticesPerVoxel = 32768;  // half of the 16-bit order limit
constexpr double kOccupiedFraction = 0.5;          // of the bounding box, for brain-like tractograms
constexpr double kMaxVoxels = 20000;
constexpr double kMinStepsPerVoxel = 3;
constexpr double kLargest = 10.0;
constexpr std::array<double, 13> kSizes = {1, 1.25, 1.5, 2, 2.5, 3, 3.5, 4, 5, 6, 7, 8, 10};

std::string format_mm(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

}  // namespace

VoxelSizeChoice choose_voxel_size(std::uint64_t points, const double lo[3], const double hi[3], double rms_step) {
  double volume = kOccupiedFraction;
  for (int c = 0; c < 3; ++c) volume *= std::max(0.0, hi[c] - lo[c]);
  if (!std::isfinite(volume)) volume = 0;
  if (!std::isfinite(rms_step)) rms_step = 0;

  double size = kLargest;
  if (points > 0 && volume > 0) size = std::min(size, std::cbrt(kTargetVerticesPerVoxel * volume / double(points)));
  const double lower = std::max(kMinStepsPerVoxel * rms_step, std::cbrt(volume / kMaxVoxels));
  size = std::max(size, lower);
  // Round down to a listed size, but not below the lower bounds (then up to the next listed one).
  double chosen = kSizes.front();
  for (double s : kSizes)
    if (s <= size) chosen = s;
  if (chosen < lower)
    for (double s : kSizes)
      if (s >= lower) {
        chosen = s;
        break;
      }
  if (chosen < lower) chosen = lower;  // beyond the list (steps longer than 3.3 mm): the bound itself

  VoxelSizeChoice choice;
  choice.size = chosen;
  choice.reason = "auto: " + format_mm(chosen) + " mm for " + std::to_string(points) + " points in " +
                  format_mm(hi[0] - lo[0]) + " x " + format_mm(hi[1] - lo[1]) + " x " + format_mm(hi[2] - lo[2]) +
                  " mm, RMS step " + format_mm(rms_step) +
                  " mm (about 32k vertices per voxel at most 10 mm, at least 3 steps, at most ~20k voxels)";
  return choice;
}

}  // namespace vxl
