// The exact tables of the .vxl an unpack writes, rebuilt from a package's streams (spec/vxlz-package-v2.md §7 steps
// 2-4), and where each voxline's points go: what the unpacker's stages (the tables, the positions, the orders) share.
#pragma once

#include <cstdint>
#include <vector>

#include "format/vxl_layout.h"
#include "format/vxl_levels.h"
#include "format/vxlz_shipping_order.h"

namespace vxl {

struct UnpackStructure {
  std::vector<std::uint64_t> strm;              // N + 1
  std::vector<VoxlineEntry> voxlines;           // L
  std::vector<std::uint8_t> starts_streamline;  // L + 1 (the last entry 1): voxline j is a streamline's first
  std::vector<VoxelEntry> voxels;               // coord, vertex and segment counts, vertex_first, order layout
  std::vector<LevelEntry> levels;               // LODS: voxel_count x (level_count - 1)
  std::uint32_t level_count = 1;
  std::uint64_t order_bytes = 0;
  // Voxline j's first vertex is voxels[voxel].vertex_first + offset_in_voxel[j] (< 2^32: a voxel's
  // vertex count is).
  std::vector<std::uint32_t> offset_in_voxel;
  // The order the points were shipped in (package spec §5.1), and how many of them the file holds: all, or for
  // the streamlines of a level alone, the first ones (a level's are shipped first).
  ShippingOrder order;
  std::uint64_t shipped_points = 0;

  bool connected(std::uint64_t j) const { return !starts_streamline[j + 1]; }
  std::uint32_t own(std::uint64_t j) const { return voxlines[j].count_flags & kVoxlineCountMask; }
  std::uint64_t first_vertex(std::uint64_t j) const {
    return voxels[voxlines[j].voxel].vertex_first + offset_in_voxel[j];
  }
};

}  // namespace vxl
