#include "converter/convert/position_packing.h"

#include "format/base/parallel.h"
#include "format/vxl_positions.h"

namespace vxl {

void pack_vertex_blocks(std::span<const VoxelEntry> voxels, std::span<float> vertices, const VoxlineEnds& ends,
                        std::span<std::uint32_t> packed, unsigned threads) {
  parallel_for(voxels.size(), threads, [&](std::uint64_t i, unsigned) {
    const VoxelEntry& v = voxels[i];
    std::uint32_t* words = packed.data() + v.vertex_first;
    pack_block(v, vertices.data() + 3 * v.vertex_first, v.vertex_count, words);
    for (std::uint32_t k = 0; k < v.vertex_count; ++k)
      if (ends.test(v.vertex_first + k)) words[k] |= kPackedVoxlineEnd;
  });
}

}  // namespace vxl
