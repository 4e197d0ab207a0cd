// `--voxel-size auto`: the voxel size chosen from the data (the point count, the extent and the step
// length), for the cheapest file and frame at the accuracy every size gives.
//
// Why cost alone decides: the trade study (README, "Speed vs accuracy") finds the `axis` mode's error
// against `exact` nearly flat over voxel sizes from 2.5 to 40 mm, so the choice is about what a size
// costs. Large voxels hold many vertices, and a voxel of more than 65 536 vertices stores its orders in 3
// or 4 bytes per entry instead of 2 (spec §5.5); small voxels cut streamlines more often, each cut adding a
// connecting vertex (about 1.25 x step / size extra vertices per point, measured), and make more voxels to
// sort every frame. The rule:
//   size = cbrt(32768 x occupied volume / points)   about half the 16-bit limit per voxel, where the
//                                                    occupied volume is taken as half the bounding box
//   at most 10 mm                                    (the paper's default; larger only costs order width)
//   at least 3 x the RMS step                        (at most ~40 % connecting vertices)
//   at least cbrt(occupied volume / 20 000)          (at most ~20 000 voxels: frame planning stays ~1 ms)
// rounded down to one of 1, 1.25, 1.5, 2, 2.5, 3, 3.5, 4, 5, 6, 7, 8, 10 mm (after the lower bounds, to a
// value not below them; 10 mm when they ask for more). The synthetic 144k set gets 10 mm, the 1M set 8 mm,
// a 10M set 4 mm. Points that no listed size can convert (an extent beyond 2^31 voxels of 10 mm, steps that
// 10 mm voxels would split into more points than the source has) are refused rather than given a size.
#pragma once

#include <cstdint>
#include <string>

namespace vxl {

struct VoxelSizeChoice {
  double size = 10.0;  // mm
  std::string reason;  // one line, for `info` and the provenance
};

// `rms_step`: the root mean square distance between consecutive points (0 when there are none). Throws
// vxl::Error (Unsupported) naming `path`, with the size to give instead, for points no listed size converts.
VoxelSizeChoice choose_voxel_size(std::uint64_t points, const double lo[3], const double hi[3], double rms_step,
                                  const std::string& path = "");

}  // namespace vxl
