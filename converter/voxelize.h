// Voxelisation: Algorithm 1 of the Voxlines paper (Osman et al.), plus the splitting of steps longer
// than a voxel at voxel faces (spec §6.3), and the per-voxel vertex blocks of spec §5.3–§5.7.
//
//   streamlines --(voxel of each point, §6.1)--> voxlines --(grouped per voxel)--> vertex blocks
//
// Work is split over threads by contiguous streamline ranges; the result does not depend on the thread
// count (voxlines keep streamline order inside each block).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "tractogram.h"
#include "vxl_layout.h"

namespace vxl {

// Called with a stage name and a fraction in [0, 1] of that stage; may be empty.
using ProgressFn = std::function<void(const char* stage, double fraction)>;

struct VoxelizeSettings {
  double voxel_size = 10.0;  // mm
  unsigned threads = 0;      // 0: all hardware threads
  ProgressFn progress;
  // Refuse (with a suggested voxel size) when splitting long steps would add more than this many
  // points per source point: a guard against a voxel size far below the step length.
  double max_synthetic_per_point = 1.0;
};

// The voxel blocks, without orders (build_orders adds those).
struct VoxelizedTractogram {
  MetaSection meta{};
  std::vector<VoxelEntry> voxels;      // sorted by (z, y, x); order_offset/flags set by build_orders
  std::vector<float> vertices;         // 3 * vertex_count
  std::vector<VoxlineEntry> voxlines;  // streamline order
  std::vector<std::uint64_t> streamline_first_voxline;  // N + 1
  std::vector<std::uint8_t> is_voxline_end;  // per vertex: 1 when it is the last vertex of a voxline
};

// Consumes the tractogram's positions (they are released once copied into the blocks, to bound peak
// memory). Throws vxl::Error (Unsupported) when a limit of spec §9 would be exceeded, with a suggestion.
VoxelizedTractogram voxelize(Tractogram&& tractogram, const VoxelizeSettings& settings);

// The integer voxel coordinate of a point (spec §6.1), exposed for tests.
inline std::int64_t voxel_coordinate(float p, double origin, double voxel_size) {
  return static_cast<std::int64_t>(std::floor((static_cast<double>(p) - origin) / voxel_size));
}

unsigned resolve_threads(unsigned requested);

}  // namespace vxl
