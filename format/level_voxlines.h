// The voxlines of one level of detail (spec §5.12, §6.5), every voxel's placed in its block: what a renderer needs
// to name the streamline of each vertex it draws at a coarse level. They are found from the level's own
// streamlines through STRM and VXLN (an eighth of the next finer level's), because a voxel's list (VXIX) holds
// the voxlines of every depth: placing a coarse level through the lists reads them all, 84M entries on a 10M set
// for the few thousand streamlines of its coarsest level.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"

namespace vxl {

class LevelVoxlines {
 public:
  // Level `level` of `file`. Throws vxl::Error (Input) naming the file when STRM, VXLN and the voxels' level
  // prefixes (LODS) do not hold together.
  LevelVoxlines(const VxlFile& file, std::uint32_t level);
  // Voxel `voxel`'s voxlines of the level, in streamline order, placed where place_voxel_voxlines places them.
  std::span<const PlacedVoxline> of_voxel(std::size_t voxel) const {
    return {placed_.data() + first_[voxel], placed_.data() + first_[voxel + 1]};
  }
  std::uint32_t level() const { return level_; }

 private:
  std::uint32_t level_ = 0;
  std::vector<std::uint64_t> first_;  // voxel_count + 1: where each voxel's voxlines start in placed_
  std::vector<PlacedVoxline> placed_;
};

}  // namespace vxl
