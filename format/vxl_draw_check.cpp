#include "format/vxl_draw_check.h"

#include <string>

#include "format/base/error.h"

namespace vxl {

void check_voxel_drawing(const VxlFile& file, std::uint32_t voxel, std::uint32_t level,
                         std::vector<std::uint8_t>& is_start) {
  const VoxelEntry& v = file.voxels()[voxel];
  const LevelEntry counts = file.level(voxel, level);
  const std::uint64_t orders_at =
      file.orders_offset() +
      level_orders_offset(v, file.levels_of(voxel), level, file.meta().stored_order_count, file.order_packing());
  is_start.assign(counts.vertex_count, 0);
  std::uint32_t starts = 0;
  for (std::uint32_t k = 0; k < file.meta().stored_order_count; ++k) {
    const OrderView o = file.order(voxel, k, level);
    for (std::uint32_t n = 0; n < o.count; ++n) {
      const std::uint32_t e = o[n];
      if (e + 1ull >= counts.vertex_count)
        throw Error(ErrorKind::Input, file.path(), orders_at,
                    "order entry out of range in voxel " + std::to_string(voxel) + " (run `voxlines verify`)");
      if (k == 0 && is_start[e] == 0) {
        is_start[e] = 1;
        ++starts;
      }
    }
  }
  if (starts != counts.segment_count)  // a repeated entry in order 0: it is no permutation
    throw Error(
        ErrorKind::Input, file.path(), orders_at,
        "order 0 of voxel " + std::to_string(voxel) + " is not a permutation of its segments (run `voxlines verify`)");
  if (file.position_encoding() != PositionEncoding::Packed) return;
  // The level's prefix of the block: its voxline-end bits are the ones the renderer draws (spec §5.4).
  const std::uint32_t* block = file.packed_vertices().data() + v.vertex_first;
  for (std::uint32_t n = 0; n < counts.vertex_count; ++n)
    if (((block[n] & kPackedVoxlineEnd) != 0) == (is_start[n] != 0) || (block[n] & kPackedReservedBit) != 0)
      throw Error(ErrorKind::Input, file.path(),
                  file.find_section(section_id("VERT"))->offset + 4 * (v.vertex_first + n),
                  "packed vertex " + std::to_string(n) + " of voxel " + std::to_string(voxel) +
                      ": voxline-end bit disagrees with order 0, or reserved bit set (run `voxlines verify`)");
}

}  // namespace vxl
