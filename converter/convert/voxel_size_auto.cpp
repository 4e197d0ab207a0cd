#include "converter/convert/voxel_size_auto.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "converter/convert/voxelize.h"
#include "format/base/error.h"

namespace vxl {
namespace {

constexpr double kTargetVerticesPerVoxel = 32768;  // half of the 16-bit order limit
constexpr double kOccupiedFraction = 0.5;          // of the bounding box, for brain-like tractograms
constexpr double kMaxVoxels = 20000;
constexpr double kMinStepsPerVoxel = 3;
constexpr double kLargest = 10.0;
constexpr std::array<double, 13> kSizes = {1, 1.25, 1.5, 2, 2.5, 3, 3.5, 4, 5, 6, 7, 8, 10};
// What the converter refuses (voxel_table.h, voxelize.h), and the measured connecting vertices a point
// gets per step / size: auto refuses what no listed size can convert.
constexpr double kMaxGridCells = 2147483647.0;
constexpr double kSyntheticPerStep = 1.25;

std::string format_mm(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

}  // namespace

VoxelSizeChoice choose_voxel_size(std::uint64_t points, const double lo[3], const double hi[3], double rms_step,
                                  const std::string& path) {
  VoxelSizeChoice choice;
  bool empty = points == 0;
  for (int c = 0; c < 3; ++c) empty = empty || !(hi[c] >= lo[c]);
  if (empty) {
    choice.reason = "auto: " + format_mm(kLargest) + " mm (no points to choose from)";
    return choice;
  }
  double extent = 0, volume = kOccupiedFraction;
  for (int c = 0; c < 3; ++c) {
    extent = std::max(extent, hi[c] - lo[c]);
    volume *= hi[c] - lo[c];
  }
  if (!std::isfinite(rms_step)) rms_step = 0;
  // What no listed size can do: refused here, with the size to give, rather than chosen and then refused.
  if (!(std::floor(extent / kLargest) + 1 < kMaxGridCells))
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "--voxel-size auto: the points span " + format_mm(extent) + " mm, more than " + format_mm(kLargest) +
                    " mm voxels (the largest it chooses) can grid in 2^31 a side; give "
                    "--voxel-size " +
                    format_mm(extent / 1e9) + " or larger");
  if (kSyntheticPerStep * rms_step / kLargest > kMaxSyntheticPerPoint)
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "--voxel-size auto: steps of " + format_mm(rms_step) + " mm (RMS) would be split at " +
                    format_mm(kLargest) +
                    " mm voxels (the largest it chooses) into more points than the source "
                    "has; give --voxel-size " +
                    format_mm(kMinStepsPerVoxel * rms_step) + " or larger");

  double size = kLargest;
  if (std::isfinite(volume) && volume > 0)
    size = std::min(size, std::cbrt(kTargetVerticesPerVoxel * volume / double(points)));
  const double lower =
      std::max(kMinStepsPerVoxel * rms_step, std::isfinite(volume) ? std::cbrt(volume / kMaxVoxels) : 0.0);
  // The largest listed size not above `size`; when that is below the lower bounds, the smallest listed size
  // meeting them; when none does, the largest (the bounds are costs, not limits).
  double chosen = kSizes.front();
  for (double s : kSizes)
    if (s <= size) chosen = s;
  std::string note;
  if (chosen < lower) {
    chosen = kSizes.back();
    for (double s : kSizes)
      if (s >= lower) {
        chosen = s;
        break;
      }
    if (chosen < lower)
      note = "; " + format_mm(lower) + " mm would meet the step and voxel-count bounds, " + format_mm(kLargest) +
             " mm is the largest it chooses";
  }
  choice.size = chosen;
  choice.reason = "auto: " + format_mm(chosen) + " mm for " + std::to_string(points) + " points in " +
                  format_mm(hi[0] - lo[0]) + " x " + format_mm(hi[1] - lo[1]) + " x " + format_mm(hi[2] - lo[2]) +
                  " mm, RMS step " + format_mm(rms_step) +
                  " mm (about 32k vertices per voxel at most 10 mm, at least 3 steps, at most ~20k voxels" + note + ")";
  return choice;
}

}  // namespace vxl
