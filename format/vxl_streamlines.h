// Rebuilds the source streamlines from a .vxl's voxel blocks by walking the voxline table (spec §5.6).
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "format/vxl_file.h"

namespace vxl {

struct WalkCallbacks {
  // Called once per streamline, in order, with its source points (synthetic face points dropped).
  std::function<void(std::uint64_t streamline, std::span<const float> xyz)> streamline;
  // Optional: called for every voxline with its voxel and its first vertex (global index), before the
  // streamline callback of the streamline it belongs to.
  std::function<void(std::uint32_t voxel, std::uint64_t first_vertex, std::uint32_t own_points, bool connected)>
      voxline;
};

// Checks the walk as it goes (table ranges, blocks consumed exactly, connecting vertices equal to the
// next voxline's first vertex, totals matching META) and throws vxl::Error (Input) on any inconsistency.
void walk_streamlines(const VxlFile& file, const WalkCallbacks& callbacks);

}  // namespace vxl
