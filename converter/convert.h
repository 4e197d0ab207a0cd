// The conversion pipeline: tractogram -> voxel blocks -> orders -> .vxl (with provenance).
#pragma once

#include <string>

#include "tractogram.h"
#include "voxelize.h"

namespace vxl {

struct ConvertSettings {
  double voxel_size = 10.0;   // mm; the paper's balance of speed and quality
  unsigned threads = 0;       // 0: all hardware threads
  std::string orders = "axis";
  ProgressFn progress;
};

struct ConvertSummary {
  std::uint64_t streamlines = 0, points = 0, voxels = 0, vertices = 0, segments = 0, synthetic_points = 0;
  double voxelize_seconds = 0, orders_seconds = 0, write_seconds = 0;
};

// Consumes the tractogram (its positions are released as soon as they are copied) and writes `out_path`
// atomically. Throws vxl::Error.
ConvertSummary convert_tractogram(Tractogram&& tractogram, const std::string& out_path, const ConvertSettings& settings);

}  // namespace vxl
